"""Expressions evaluated for many candidate scenes at once: the candidate sampler's values
(candidates.py).

The batched sampler's compiler (batch_values.py), extended with what a whole-scene
rejection test reads: sizes that change between candidates (`self.width`, ranges,
TruncatedNormal), comparisons, `and`/`or`/`not`, the math functions and `distance from`.
Booleans are (n, 1) arrays of 0.0 and 1.0. Anything else is `Unbatchable`, and the spec's
joint law is drawn by Gibbs sweeps instead.
"""

from __future__ import annotations

import operator
from typing import Any, Callable

import numpy as np

from prsc.constraints.distributions import truncated_normal, truncated_normal_mass
from prsc.ir import model as ir
from prsc.ir.program import Program
from prsc.sampling.batch_values import BatchCompiler, BatchState, BatchValue, Unbatchable, _memoised, draw_site
from prsc.sampling.counter_stream import uniforms

_DIMENSIONS = ("width", "length", "height")
_COMPARE: dict[str, Callable[[Any, Any], Any]] = {
    "<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge, "==": operator.eq, "!=": operator.ne,
}
_UNIT = (np.zeros(1), np.ones(1))  # the bounds of a boolean
# Functions of numbers as the scalar evaluator has them (prsc/constraints/evaluate.py); their
# bounds come from the arguments' (_call_bounds). tan and atan2 are not vectorised here.
_FUNCTIONS: dict[str, Callable[..., np.ndarray]] = {
    "abs": np.abs, "hypot": np.hypot, "sqrt": np.sqrt, "min": np.minimum, "max": np.maximum,
    "sin": np.sin, "cos": np.cos,
}


class CandidateState(BatchState):
    """One round's evaluation state: per candidate its key, placed boxes and draws."""

    __slots__ = ("rotations", "dims", "reaches", "active")

    def __init__(self, keys: np.ndarray) -> None:
        super().__init__(keys)
        self.rotations: dict[str, np.ndarray] = {}  # object name -> (n, 3, 3)
        self.dims: dict[str, np.ndarray] = {}  # object name -> (n, 3)
        self.reaches: dict[str, np.ndarray] = {}  # object name -> (n, 3): half extents of its axis-aligned box
        self.active: np.ndarray | None = None  # (n, soft requires): which the candidate enforces


class CandidateCompiler(BatchCompiler):
    """Compiles IR expressions over the objects a candidate round places (sizes included)."""

    def __init__(self, program: Program, objects: dict[str, tuple[np.ndarray, np.ndarray, Any]]) -> None:
        super().__init__(program, objects)
        self.sizes: dict[str, dict[str, BatchValue]] = {}  # object -> dimension -> its value, as compiled so far

    def _c_PropertyRef(self, e: ir.PropertyRef) -> BatchValue:
        if isinstance(e.target, ir.ObjectRef) and e.prop in _DIMENSIONS:
            size = self.sizes.get(e.target.name, {}).get(e.prop)
            if size is None:
                raise Unbatchable(f"{e.target.name}.{e.prop} before it is drawn")
            return size
        return super()._c_PropertyRef(e)

    def _c_Compare(self, e: ir.Compare) -> BatchValue:
        a, b = self.compile(e.left), self.compile(e.right)
        if a.vector or b.vector or e.op not in _COMPARE:
            raise Unbatchable(f"{e.op!r} on these operands")
        fa, fb, test = a.fn, b.fn, _COMPARE[e.op]
        return BatchValue(lambda state: test(fa(state), fb(state)).astype(float), *_UNIT)

    def _c_BoolOp(self, e: ir.BoolOp) -> BatchValue:
        fns = [self._truth(o) for o in e.operands]
        join = np.logical_and if e.op == "and" else np.logical_or

        def combined(state: BatchState) -> np.ndarray:
            out = fns[0](state) != 0.0
            for fn in fns[1:]:
                out = join(out, fn(state) != 0.0)
            return out.astype(float)

        return BatchValue(combined, *_UNIT)

    def _c_UnaryOp(self, e: ir.UnaryOp) -> BatchValue:
        if e.op != "not":
            return super()._c_UnaryOp(e)
        fn = self._truth(e.operand)
        return BatchValue(lambda state: (fn(state) == 0.0).astype(float), *_UNIT)

    def _truth(self, e: ir.Expr) -> Callable[[BatchState], np.ndarray]:
        value = self.compile(e)
        if value.vector:
            raise Unbatchable("a vector as a truth value")
        return value.fn

    def _c_Call(self, e: ir.Call) -> BatchValue:
        func = _FUNCTIONS.get(e.func)
        args = [self.compile(a) for a in e.args]
        if func is None or any(a.vector for a in args) or not args:
            raise Unbatchable(f"the function {e.func!r} here")
        if e.func in ("hypot", "min", "max") and len(args) != 2 or e.func not in ("hypot", "min", "max") and len(args) != 1:
            raise Unbatchable(f"{e.func} with {len(args)} arguments")
        if e.func == "sqrt" and args[0].lo[0] < 0:
            raise Unbatchable("sqrt of a value that may be negative")
        fns = [a.fn for a in args]
        lo, hi = _call_bounds(e.func, args)
        return BatchValue(lambda state: func(*(f(state) for f in fns)), lo, hi)

    def _c_Distance(self, e: ir.Distance) -> BatchValue:
        a, b = self.compile(e.source), self.compile(e.target)
        if not (a.vector and b.vector):
            raise Unbatchable("`distance from` between values that are not points")
        fa, fb = a.fn, b.fn
        reach = float(np.linalg.norm(np.maximum(np.abs(a.hi - b.lo), np.abs(b.hi - a.lo))))
        return BatchValue(lambda state: np.linalg.norm(fa(state) - fb(state), axis=1, keepdims=True),
                          np.zeros(1), np.array([reach]))

    def _c_Distribution(self, e: ir.Distribution) -> BatchValue:
        if e.kind == "truncnormal":
            return self._truncnormal(e)
        if e.kind == "discrete":
            return self._discrete(e)
        return super()._c_Distribution(e)

    def _constants(self, exprs: tuple[ir.Expr, ...], what: str) -> list[float]:
        values = [self.compile(a) for a in exprs]
        if any(v.constant is None or v.vector for v in values):
            raise Unbatchable(f"{what} that are not constant numbers")
        return [float(v.constant[0]) for v in values]

    def _truncnormal(self, e: ir.Distribution) -> BatchValue:
        mean, sd, low, high = self._constants(e.args, "TruncatedNormal's arguments")
        try:
            mass = truncated_normal_mass(mean, sd, low, high)
        except ValueError:
            raise Unbatchable("a TruncatedNormal the scalar sampler refuses") from None
        site = draw_site(e.draw_id)

        def draw(state: BatchState) -> np.ndarray:
            return truncated_normal(mean, sd, low, high, mass, uniforms(state.keys, site, 1))  # the scalar draw's

        return _memoised(e.draw_id, draw, np.array([low]), np.array([high]))

    def _discrete(self, e: ir.Distribution) -> BatchValue:
        options = self._constants(e.args, "Discrete's options")
        weights = self._constants(e.weights, "Discrete's weights")
        total = sum(weights)
        if any(w < 0 for w in weights) or not total > 0 or len(weights) != len(options):
            raise Unbatchable("Discrete weights the scalar sampler refuses")
        cumulative, table, site = np.cumsum(weights), np.array(options), draw_site(e.draw_id)

        def draw(state: BatchState) -> np.ndarray:
            # The scalar draw's rule: the first option whose cumulative weight exceeds u * total.
            which = np.searchsorted(cumulative, uniforms(state.keys, site, 1) * total, side="right")
            return table[np.minimum(which, len(table) - 1)]

        return _memoised(e.draw_id, draw, table.min(keepdims=True), table.max(keepdims=True))


def _call_bounds(func: str, args: list[BatchValue]) -> tuple[np.ndarray, np.ndarray]:
    """Bounds of a function's value from its arguments' bounds."""
    if func in ("sin", "cos"):
        return -np.ones(1), np.ones(1)
    if func == "abs":
        a = args[0]
        top = np.maximum(np.abs(a.lo), np.abs(a.hi))
        low = np.where((a.lo <= 0) & (a.hi >= 0), 0.0, np.minimum(np.abs(a.lo), np.abs(a.hi)))
        return low, top
    if func == "sqrt":
        return np.sqrt(args[0].lo), np.sqrt(args[0].hi)
    if func == "hypot":
        top = np.hypot(*(np.maximum(np.abs(a.lo), np.abs(a.hi)) for a in args))
        return np.zeros(1), top
    pick = np.minimum if func == "min" else np.maximum
    return pick(args[0].lo, args[1].lo), pick(args[0].hi, args[1].hi)
