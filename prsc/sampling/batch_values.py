"""Expressions evaluated for many scenes at once: the batched sampler's values (batched.py).

A subset of the language compiles: numbers and vectors, + - * / and unary minus as the
scalar evaluator allows them (prsc/constraints/operations.py), ranges and `Uniform` over
numbers, variables, and the position, coordinates and size of objects the batch places.
Anything else is `Unbatchable`, and the spec is sampled one scene at a time instead.

Each value carries bounds valid in every scene (interval arithmetic), so the batch plan
can prove once that, for instance, an `at` point never leaves the workspace. Numbers are
(n, 1) arrays and vectors (n, 3); all arithmetic is elementwise, so a scene's values do not
depend on how many scenes share a batch.
"""

from __future__ import annotations

import operator
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from prsc.ir import model as ir
from prsc.ir.program import Program
from prsc.sampling.counter_stream import uniforms


class Unbatchable(Exception):
    """An expression (or spec) the batched sampler does not vectorise; the message says what."""


class BatchState:
    """One batch's evaluation state: scene keys, placed positions, memoised draws."""

    __slots__ = ("keys", "positions", "draws", "variables")

    def __init__(self, keys: np.ndarray) -> None:
        self.keys = keys
        self.positions: dict[str, np.ndarray] = {}  # object name -> (n, 3)
        self.draws: dict[int, np.ndarray] = {}  # draw id -> (n, 1), one draw per scene as in the language
        self.variables: dict[str, np.ndarray] = {}


@dataclass(frozen=True)
class BatchValue:
    """A vectorised expression: `fn(state)` is (n, 1) numbers or (n, 3) vectors, within [lo, hi] in every scene."""

    fn: Callable[[BatchState], np.ndarray] = field(repr=False)
    lo: np.ndarray
    hi: np.ndarray
    constant: Any = None  # the value itself when it is the same in every scene

    @property
    def vector(self) -> bool:
        """Whether it is a 3-vector (else a number)."""
        return self.lo.shape == (3,)


def draw_site(draw_id: int) -> int:
    """The counter stream's site of a distribution (odd; even sites are the objects', batched.py)."""
    return 2 * draw_id + 1


def _const(value: np.ndarray | float) -> BatchValue:
    array = np.atleast_1d(np.asarray(value, dtype=float))
    row = array[None, :]
    return BatchValue(lambda state: row, array, array, constant=array)


class BatchCompiler:
    """Compiles IR expressions of one program over the objects a batch places."""

    def __init__(self, program: Program, objects: dict[str, tuple[np.ndarray, np.ndarray, tuple[float, float, float]]]) -> None:
        # objects: name -> (lo, hi) of its centre in every scene and its (static) size, for
        # the objects placed so far; filled in by the batch plan object by object.
        self.objects = objects
        self._variables = {v.name: v for v in program.variables}
        self._compiled: dict[str, BatchValue] = {}

    def compile(self, expr: ir.Expr) -> BatchValue:
        """A vectorised expression, or Unbatchable."""
        method = getattr(self, "_c_" + type(expr).__name__, None)
        if method is None:
            raise Unbatchable(f"a {type(expr).__name__} expression")
        return method(expr)

    def _c_Const(self, e: ir.Const) -> BatchValue:
        if isinstance(e.value, bool) or not isinstance(e.value, (int, float)):
            raise Unbatchable("a value that is not a number")
        return _const(float(e.value))

    def _c_VectorExpr(self, e: ir.VectorExpr) -> BatchValue:
        parts = [self.compile(c) for c in (e.x, e.y, e.z)]
        if any(p.vector for p in parts):
            raise Unbatchable("a vector component that is a vector")
        if all(p.constant is not None for p in parts):
            return _const(np.concatenate([p.constant for p in parts]))
        fx, fy, fz = (p.fn for p in parts)

        def vector(state: BatchState) -> np.ndarray:
            x, y, z = fx(state), fy(state), fz(state)
            n = max(len(x), len(y), len(z))
            out = np.empty((n, 3))
            out[:, 0:1], out[:, 1:2], out[:, 2:3] = x, y, z
            return out

        return BatchValue(vector, np.concatenate([p.lo for p in parts]), np.concatenate([p.hi for p in parts]))

    def _c_ObjectRef(self, e: ir.ObjectRef) -> BatchValue:
        return self._position(e.name)

    def _position(self, name: str) -> BatchValue:
        if name not in self.objects:
            raise Unbatchable(f"{name}'s position before it is placed")
        lo, hi, _ = self.objects[name]
        if np.array_equal(lo, hi):
            return _const(lo)
        return BatchValue(lambda state: state.positions[name], lo, hi)

    def _c_PropertyRef(self, e: ir.PropertyRef) -> BatchValue:
        if not isinstance(e.target, ir.ObjectRef):
            raise Unbatchable("a property of something other than an object")
        name, prop = e.target.name, e.prop
        if prop == "position":
            return self._position(name)
        if prop in ("x", "y", "z"):
            axis = "xyz".index(prop)
            position = self._position(name)
            if position.constant is not None:
                return _const(position.constant[axis])
            fn = position.fn
            return BatchValue(lambda state: fn(state)[:, axis:axis + 1], position.lo[axis:axis + 1], position.hi[axis:axis + 1])
        if prop in ("width", "length", "height") and name in self.objects:
            return _const(self.objects[name][2][("width", "length", "height").index(prop)])
        raise Unbatchable(f"the property {prop!r}")

    def _c_VarRef(self, e: ir.VarRef) -> BatchValue:
        name = e.name
        if name not in self._compiled:
            variable = self._variables.get(name)
            if variable is None:
                raise Unbatchable(f"the variable {name!r}")
            self._compiled[name] = self.compile(variable.value)  # draws inside are memoised by draw id
        return self._compiled[name]

    def _c_UnaryOp(self, e: ir.UnaryOp) -> BatchValue:
        if e.op not in ("-", "+"):
            raise Unbatchable(f"unary {e.op!r}")
        inner = self.compile(e.operand)
        if e.op == "+":
            return inner
        if inner.constant is not None:
            return _const(-inner.constant)
        fn = inner.fn
        return BatchValue(lambda state: -fn(state), -inner.hi, -inner.lo)

    def _c_BinOp(self, e: ir.BinOp) -> BatchValue:
        a, b, op = self.compile(e.left), self.compile(e.right), e.op
        # The combinations the scalar evaluator accepts (operations._binary), nothing more.
        if op not in ("+", "-", "*", "/") or (a.vector and not b.vector and op in "+-") or (
            b.vector and (not a.vector or op in "*/")
        ):
            raise Unbatchable(f"{op!r} on these operands")
        if op == "/" and b.lo[0] <= 0.0 <= b.hi[0]:
            raise Unbatchable("a division by a value that may be zero")
        lo, hi = _interval(op, a, b)
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            raise Unbatchable("a value that may overflow")
        if a.constant is not None and b.constant is not None:
            return _const(_apply(op, a.constant, b.constant))
        fa, fb = a.fn, b.fn
        return BatchValue(lambda state: _apply(op, fa(state), fb(state)), lo, hi)

    def _c_Distribution(self, e: ir.Distribution) -> BatchValue:
        draw_id, site = e.draw_id, draw_site(e.draw_id)
        if e.kind == "range":
            low, high = (self.compile(a) for a in e.args)
            if low.vector or high.vector or not low.hi[0] <= high.lo[0]:
                raise Unbatchable("a range whose bounds may cross")
            fl, fh = low.fn, high.fn

            def draw_range(state: BatchState) -> np.ndarray:
                u = uniforms(state.keys, site, 1)
                lo, hi = fl(state), fh(state)
                return lo + (hi - lo) * u  # the scalar draw's formula (distributions.py)

            return _memoised(draw_id, draw_range, low.lo, high.hi)
        if e.kind == "uniform":
            options = [self.compile(a) for a in e.args]
            if not options or any(o.constant is None or o.vector for o in options):
                raise Unbatchable("Uniform over values that are not constant numbers")
            table = np.array([o.constant[0] for o in options])

            def draw_option(state: BatchState) -> np.ndarray:
                u = uniforms(state.keys, site, 1)
                which = np.minimum((u * len(table)).astype(np.int64), len(table) - 1)
                return table[which]

            return _memoised(draw_id, draw_option, table.min(keepdims=True), table.max(keepdims=True))
        raise Unbatchable(f"a {e.kind} distribution")


def _memoised(draw_id: int, draw: Callable[[BatchState], np.ndarray], lo: np.ndarray, hi: np.ndarray) -> BatchValue:
    """One draw per scene however many places read it (the language's rule)."""

    def memoised(state: BatchState) -> np.ndarray:
        value = state.draws.get(draw_id)
        if value is None:
            value = state.draws[draw_id] = draw(state)
        return value

    return BatchValue(memoised, lo, hi)


_OPERATORS = {"+": operator.add, "-": operator.sub, "*": operator.mul, "/": operator.truediv}


def _apply(op: str, a: Any, b: Any) -> Any:
    return _OPERATORS[op](a, b)


def _interval(op: str, a: BatchValue, b: BatchValue) -> tuple[np.ndarray, np.ndarray]:
    """Bounds of `a op b` from the operands' bounds (per component)."""
    if op == "+":
        return a.lo + b.lo, a.hi + b.hi
    if op == "-":
        return a.lo - b.hi, a.hi - b.lo
    blo, bhi = (b.lo, b.hi) if op == "*" else (1.0 / b.hi, 1.0 / b.lo)
    corners = np.stack([a.lo * blo, a.lo * bhi, a.hi * blo, a.hi * bhi])
    return corners.min(axis=0), corners.max(axis=0)
