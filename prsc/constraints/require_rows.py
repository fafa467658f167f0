"""Lowering `require` conditions that are linear in one object's position to rows.

The object is the one placed last among those the condition mentions; everything about
other objects is concrete by then. Face points of that object are affine in its position
when its rotation and size are known before its position, so e.g.
`(right tr_1).x + 0.2 < table.x` becomes the row e_x . p <= table.x - 0.2 - width/2.
Anything else (products of positions, `or`, functions of positions) is not lowered: the
caller checks it by rejection.

A condition that is not linear may still imply rows: `distance from A to B < r` implies
|A - B| <= r along each axis (the box around the ball). implied_condition returns those;
the sampler draws from the smaller region they leave and still checks the condition, so
the law is the same, with fewer rejections.

Coefficients have six columns: the target's position p, then the position t of an
optional `anchor` object kept symbolic too, so a condition compiles to rows
`A p + B t <= b`; with B = -A the rows move rigidly with the anchor.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from prsc.constraints.context import SceneContext
from prsc.constraints.evaluate import Compiled, ExprCompiler
from prsc.constraints.operations import binary, describe, truthy
from prsc.constraints.operations import face_point as _face_point_value
from prsc.constraints.values import ObjectValue, OrientedPoint, as_position
from prsc.errors import PrscError, Span
from prsc.ir import model as ir

_FLIP = {"<": ">", "<=": ">=", ">": "<", ">=": "<=", "==": "!=", "!=": "=="}
_NEGATE = {"<": ">=", "<=": ">", ">": "<=", ">=": "<", "==": "!=", "!=": "=="}


@dataclass(frozen=True)
class Affine:
    """coef @ (p, t) + const: coef (6,) for a scalar, (3, 6) for a vector."""

    coef: np.ndarray
    const: Any

    @property
    def is_vector(self) -> bool:
        """Whether this is a vector (not a scalar) affine form."""
        return self.coef.ndim == 2


AffFn = Callable[[SceneContext], Any]  # returns an Affine or a plain value


def mentioned_objects(expr: ir.Expr) -> set[str]:
    """Names of every object an expression refers to."""
    found: set[str] = set()

    def walk(node: Any) -> None:
        if isinstance(node, ir.ObjectRef):
            found.add(node.name)
        if isinstance(node, ir.Expr):
            for value in vars(node).values():
                if isinstance(value, ir.Expr):
                    walk(value)
                elif isinstance(value, tuple):
                    for item in value:
                        if isinstance(item, ir.Expr):
                            walk(item)
                        elif isinstance(item, tuple):
                            for sub in item:
                                if isinstance(sub, ir.Expr):
                                    walk(sub)

    walk(expr)
    return found


class _NotLinear(Exception):
    """The condition is not linear in the target's position."""


class AffineCompiler:
    """Compiles a condition into rows on the target object's position, or raises _NotLinear."""

    def __init__(self, compiler: ExprCompiler, target: str, anchor: str | None = None) -> None:
        self.compiler = compiler
        self.target = target
        self.anchor = anchor

    def _symbolic(self, e: ir.Expr) -> bool:
        """Whether e mentions the target or the anchor (whose positions stay symbolic)."""
        names = mentioned_objects(e)
        return self.target in names or (self.anchor is not None and self.anchor in names)

    # -- values: closures returning an Affine (involves p) or a plain value
    def value(self, e: ir.Expr) -> tuple[AffFn, bool]:
        """(fn, is_affine): fn(ctx) gives an Affine when is_affine, else a plain value."""
        if not self._symbolic(e):
            c: Compiled = self.compiler.compile(e)
            return c.fn, False
        span = e.span
        variable = _variable_of(e, self.target, self.anchor)
        if variable is not None and isinstance(e, ir.PropertyRef):
            name, block = variable
            if e.prop == "position":
                return (lambda ctx: Affine(block, np.zeros(3))), True
            if e.prop in ("x", "y", "z"):
                row = block["xyz".index(e.prop)]
                return (lambda ctx: Affine(row, 0.0)), True
            if e.prop == "orientation":
                raise _NotLinear
            c = self.compiler.compile(e)  # width etc.: known before the position
            return c.fn, False
        if variable is not None and isinstance(e, ir.FacePoint):
            name, block = variable
            words = e.words

            def face(ctx: SceneContext) -> Affine:
                obj = ctx.objects[name]
                stand_in = ObjectValue(name, "", span, np.zeros(3), obj.rotation, obj.dims)
                offset = _face_point_value(stand_in, words, span).position
                return Affine(block, offset)

            return face, True
        if isinstance(e, ir.PropertyRef):
            inner, aff = self.value(e.target)
            if not aff:
                raise _NotLinear
            prop = e.prop
            if prop == "position":
                return inner, True
            if prop in ("x", "y", "z"):
                i = "xyz".index(prop)

                def component(ctx: SceneContext) -> Affine:
                    a = inner(ctx)
                    if not a.is_vector:
                        raise PrscError(f"{describe(1.0)} has no attribute {prop!r}", span)
                    return Affine(a.coef[i], float(a.const[i]))

                return component, True
            raise _NotLinear
        if isinstance(e, ir.RelativeTo):
            return self._relative(e)
        if isinstance(e, ir.BinOp):
            return self._binop(e)
        if isinstance(e, ir.UnaryOp) and e.op in ("-", "+"):
            inner, aff = self.value(e.operand)
            sign = -1.0 if e.op == "-" else 1.0
            if not aff:
                return (lambda ctx: binary("*", inner(ctx), sign, span)), False
            return (lambda ctx: _scale(inner(ctx), sign)), True
        raise _NotLinear

    def _relative(self, e: ir.RelativeTo) -> tuple[AffFn, bool]:
        variable = _variable_of(e.frame, self.target, self.anchor) if isinstance(e.frame, ir.ObjectRef) else None
        if variable is not None and not self._symbolic(e.value):
            name, block = variable
            vf = self.compiler.compile(e.value).fn

            def rel_self(ctx: SceneContext) -> Affine:
                obj = ctx.objects[name]
                v = as_position(vf(ctx))
                if v is None:
                    raise PrscError("'relative to' needs a vector on its left", e.span)
                return Affine(block, obj.rotation @ v)

            return rel_self, True
        if not self._symbolic(e.frame):
            inner, aff = self.value(e.value)
            ff = self.compiler.compile(e.frame).fn

            def rel_other(ctx: SceneContext) -> Affine:
                a = inner(ctx)
                frame = ff(ctx)
                if isinstance(frame, (ObjectValue, OrientedPoint)):
                    rot = frame.rotation
                    return Affine(rot @ a.coef, as_position(frame) + rot @ a.const)
                return Affine(a.coef, frame + a.const)

            return rel_other, True
        raise _NotLinear

    def _binop(self, e: ir.BinOp) -> tuple[AffFn, bool]:
        lf, la = self.value(e.left)
        rf, ra = self.value(e.right)
        op, span = e.op, e.span
        if not la and not ra:  # e.g. `b.width * b.height`: the target's size, not its position
            return (lambda ctx: binary(op, lf(ctx), rf(ctx), span)), False
        if op in ("+", "-"):
            sign = 1.0 if op == "+" else -1.0

            def add(ctx: SceneContext) -> Affine:
                left, right = _lift(lf(ctx), la, span), _lift(rf(ctx), ra, span)
                if left.is_vector != right.is_vector:
                    raise PrscError(f"cannot apply {op!r} to a vector and a number", span)
                return Affine(left.coef + sign * right.coef, left.const + sign * right.const)

            return add, True
        if op == "*" and not (la and ra):
            aff_f, plain_f = (lf, rf) if la else (rf, lf)

            def mul(ctx: SceneContext) -> Affine:
                k = plain_f(ctx)
                if isinstance(k, bool) or not isinstance(k, (int, float)):
                    raise PrscError(f"cannot multiply a position by {describe(k)}", span)
                return _scale(aff_f(ctx), float(k))

            return mul, True
        if op == "/" and la and not ra:

            def div(ctx: SceneContext) -> Affine:
                k = rf(ctx)
                if isinstance(k, bool) or not isinstance(k, (int, float)):
                    raise PrscError(f"cannot divide a position by {describe(k)}", span)
                if k == 0:
                    raise PrscError("division by zero", span)
                return _scale(lf(ctx), 1.0 / float(k))

            return div, True
        raise _NotLinear

    # -- conditions: closures returning (A rows, b, C rows, d)
    def condition(self, e: ir.Expr) -> Callable[[SceneContext], tuple[list, list, list, list]]:
        """Rows (le_rows, le_rhs, eq_rows, eq_rhs) meaning the condition holds."""
        if not self._symbolic(e):
            f = self.compiler.compile(e).fn
            span = e.span

            def plain(ctx: SceneContext) -> tuple[list, list, list, list]:
                ok = truthy(f(ctx), span)
                return ([np.zeros(6)], [0.0 if ok else -1.0], [], [])

            return plain
        if isinstance(e, ir.BoolOp) and e.op == "and":
            return _conjunction([self.condition(o) for o in e.operands])
        if isinstance(e, ir.UnaryOp) and e.op == "not" and isinstance(e.operand, ir.Compare):
            inner = e.operand
            return self._compare(_NEGATE[inner.op], inner.left, inner.right, inner.span)
        if isinstance(e, ir.Compare):
            return self._compare(e.op, e.left, e.right, e.span)
        raise _NotLinear

    def implied(self, e: ir.Expr) -> Callable[[SceneContext], tuple[list, list, list, list]] | None:
        """Rows every position meeting a condition that is not linear meets, or None (none known)."""
        if isinstance(e, ir.BoolOp) and e.op == "and":
            parts = []
            for operand in e.operands:
                try:
                    parts.append(self.condition(operand))
                except _NotLinear:
                    part = self.implied(operand)
                    if part is not None:
                        parts.append(part)
            return _conjunction(parts) if parts else None
        if isinstance(e, ir.UnaryOp) and e.op == "not" and isinstance(e.operand, ir.Compare):
            inner = e.operand
            return self.implied(ir.Compare(inner.span, inner.type, _NEGATE[inner.op], inner.left, inner.right))
        if not isinstance(e, ir.Compare):
            return None
        if e.op in ("<", "<=") and isinstance(e.left, ir.Distance):
            distance, bound = e.left, e.right
        elif e.op in (">", ">=") and isinstance(e.right, ir.Distance):
            distance, bound = e.right, e.left
        else:
            return None
        if self._symbolic(bound):
            return None
        try:
            (sf, sa), (tf, ta) = self.value(_position(distance.source)), self.value(_position(distance.target))
        except _NotLinear:
            return None
        rf, span = self.compiler.compile(bound).fn, e.span

        def box(ctx: SceneContext) -> tuple[list, list, list, list]:
            a, b = _lift(sf(ctx), sa, span), _lift(tf(ctx), ta, span)
            radius = rf(ctx)
            if isinstance(radius, bool) or not isinstance(radius, (int, float)):
                raise PrscError(f"a distance is compared with {describe(radius)}", span)
            coef, const = a.coef - b.coef, np.asarray(a.const - b.const, dtype=float)
            # |coef_i . (p, t) + const_i| <= radius on each axis i
            return ([*coef, *(-coef)], [*(radius - const), *(radius + const)], [], [])

        return box

    def _compare(self, op: str, left: ir.Expr, right: ir.Expr, span: Span) -> Callable[[SceneContext], tuple[list, list, list, list]]:
        if op == "!=":
            raise _NotLinear
        lf, la = self.value(left)
        rf, ra = self.value(right)

        def rows(ctx: SceneContext) -> tuple[list, list, list, list]:
            diff_l = _lift(lf(ctx), la, span)
            diff_r = _lift(rf(ctx), ra, span)
            if diff_l.is_vector or diff_r.is_vector:
                if op != "==" or not (diff_l.is_vector and diff_r.is_vector):
                    raise PrscError(f"cannot compare vectors with {op!r}", span)
                coef = diff_l.coef - diff_r.coef
                const = diff_l.const - diff_r.const
                return ([], [], list(coef), list(-const))
            coef = diff_l.coef - diff_r.coef
            const = float(diff_l.const - diff_r.const)
            # coef.p + const  op  0
            if op in ("<", "<="):
                return ([coef], [-const], [], [])
            if op in (">", ">="):
                return ([-coef], [const], [], [])
            return ([], [], [coef], [-const])

        return rows


def _conjunction(parts: list[Callable[[SceneContext], tuple[list, list, list, list]]]) -> Callable[[SceneContext], tuple[list, list, list, list]]:
    """The rows of all parts together."""

    def conj(ctx: SceneContext) -> tuple[list, list, list, list]:
        out: tuple[list, list, list, list] = ([], [], [], [])
        for part in parts:
            for acc, new in zip(out, part(ctx)):
                acc.extend(new)
        return out

    return conj


def _position(e: ir.Expr) -> ir.Expr:
    """An operand of `distance`: an object stands for its position."""
    return ir.PropertyRef(e.span, ir.Type.VECTOR, e, "position") if e.type == ir.Type.OBJECT else e


def _scale(a: Any, k: float) -> Affine:
    if not isinstance(a, Affine):
        raise _NotLinear
    return Affine(a.coef * k, a.const * k)


def _lift(v: Any, is_affine: bool, span: Span) -> Affine:
    """An Affine from a value (a plain number or vector has zero coefficients)."""
    if is_affine:
        return v
    if isinstance(v, bool):
        raise PrscError("cannot use a bool in a linear condition", span)
    if isinstance(v, (int, float)):
        return Affine(np.zeros(6), float(v))
    pos = as_position(v)
    if pos is not None and not isinstance(v, ObjectValue):
        return Affine(np.zeros((3, 6)), np.asarray(pos, dtype=float))
    raise PrscError(f"cannot use {describe(v)} in a linear condition", span)


_BLOCKS = (np.hstack([np.eye(3), np.zeros((3, 3))]), np.hstack([np.zeros((3, 3)), np.eye(3)]))


def _variable_of(e: ir.Expr, target: str, anchor: str | None) -> tuple[str, np.ndarray] | None:
    """(name, coefficient block) when e is the target's or the anchor's position, a face point or the object."""
    inner = e.target if isinstance(e, (ir.PropertyRef, ir.FacePoint)) else e
    if not isinstance(inner, ir.ObjectRef):
        return None
    if inner.name == target:
        return target, _BLOCKS[0]
    if anchor is not None and inner.name == anchor:
        return anchor, _BLOCKS[1]
    return None


def lower_condition(
    compiler: ExprCompiler, condition: ir.Expr, target: str, anchor: str | None = None
) -> Callable[[SceneContext], tuple[list, list, list, list]] | None:
    """Rows (six columns: p, then the anchor's t) for a condition linear in them, or None when it is not."""
    try:
        return AffineCompiler(compiler, target, anchor).condition(condition)
    except _NotLinear:
        return None


def implied_condition(
    compiler: ExprCompiler, condition: ir.Expr, target: str, anchor: str | None = None
) -> Callable[[SceneContext], tuple[list, list, list, list]] | None:
    """Rows (as lower_condition's) that a condition which is not linear implies, or None."""
    return AffineCompiler(compiler, target, anchor).implied(condition)


def constant_apart_from(compiler: ExprCompiler, expr: ir.Expr, names: set[str]) -> bool:
    """Whether every part of expr that mentions none of `names` is the same in every scene."""
    if not (mentioned_objects(expr) & names):
        return compiler.compile(expr).const
    if isinstance(expr, ir.ObjectRef):
        return True
    for value in vars(expr).values():
        items = value if isinstance(value, tuple) else (value,)
        for item in items:
            if isinstance(item, ir.Expr) and not constant_apart_from(compiler, item, names):
                return False
    return True


__all__ = ["Affine", "constant_apart_from", "implied_condition", "lower_condition", "mentioned_objects"]
