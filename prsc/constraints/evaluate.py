"""Compile IR expressions to closures `fn(ctx) -> value`, folding constants.

A subexpression whose value cannot change from scene to scene (literals, arithmetic on
them, properties of objects whose value is already known at compile time) is evaluated
once here; everything else becomes a small closure. Distributions are memoised per scene
by draw_id (docs/language.md section 8: one draw per scene, shared by all uses).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from operator import attrgetter
from typing import Any, Callable

import numpy as np

from prsc.constraints import regions
from prsc.constraints.context import SceneContext
from prsc.constraints.distributions import sampler_for
from prsc.constraints.operations import (
    arith_operand, as_number, attribute, binary, compare, describe, distance, error_at, face_point, finite, is_number,
    is_vector, relative_to, truthy,
)
from prsc.constraints.values import ObjectValue, RegionValue
from prsc.errors import PrscError
from prsc.ir import model as ir
from prsc.ir.program import Program, SelfRef

Fn = Callable[[SceneContext], Any]
_MISSING = object()
_DRAWS = attrgetter("draws")  # the context's memo of distribution values, by draw id
_VARIABLES = attrgetter("variables")  # and of random global variables, by name

_MATH: dict[str, Callable[..., float]] = {
    "sin": math.sin,
    "cos": math.cos,
    "tan": math.tan,
    "sqrt": math.sqrt,
    "abs": abs,
    "min": min,
    "max": max,
    "hypot": math.hypot,
    "atan2": math.atan2,
}


@dataclass(frozen=True)
class Compiled:
    """A compiled expression: `fn(ctx)`; when `const`, `value` is its value in every scene."""

    fn: Fn
    const: bool
    value: Any = None


def constant(value: Any) -> Compiled:
    """A compiled constant."""
    return Compiled(lambda ctx: value, True, value)


class StaticFacts:
    """What is known about objects at compile time (filled in object by object by lowering)."""

    def __init__(self) -> None:
        self.positions: dict[str, np.ndarray] = {}
        self.rotations: dict[str, np.ndarray] = {}
        self.props: dict[str, dict[str, Any]] = {}
        # Objects whose position, rotation and size are all known: stand-ins for folding.
        self.objects: dict[str, ObjectValue] = {}

    def prop(self, name: str, prop: str) -> Any:
        """The known value of an object's property, else _MISSING."""
        if prop == "position":
            return self.positions.get(name, _MISSING)
        if prop == "orientation":
            return self.rotations.get(name, _MISSING)
        if prop in ("x", "y", "z"):
            pos = self.positions.get(name)
            return _MISSING if pos is None else float(pos["xyz".index(prop)])
        return self.props.get(name, {}).get(prop, _MISSING)


def _once_per_scene(
    fn: Fn, key: Any, memo: Callable[[SceneContext], dict], remember: Callable[[SceneContext, Any, Any], None]
) -> Fn:
    """fn evaluated at most once per scene: its value is kept in the context's `memo` by `remember`."""

    def memoised(ctx: SceneContext) -> Any:
        value = memo(ctx).get(key, _MISSING)
        if value is _MISSING:
            value = fn(ctx)
            remember(ctx, key, value)
        return value

    return memoised



# ---------------------------------------------------------------- compiler


class ExprCompiler:
    """Compiles the expressions of one Program; knows variables and static object facts."""

    def __init__(self, program: Program, facts: StaticFacts | None = None) -> None:
        self.program = program
        self.facts = facts if facts is not None else StaticFacts()
        self._variables = {v.name: v for v in program.variables}
        self._var_compiled: dict[str, Compiled] = {}
        self._var_busy: set[str] = set()

    # -- entry point
    def compile(self, expr: ir.Expr) -> Compiled:
        """Compile one expression."""
        method = getattr(self, "_c_" + type(expr).__name__, None)
        if method is None:
            raise PrscError(f"unsupported expression ({type(expr).__name__})", expr.span)
        return method(expr)

    # -- leaves
    def _c_Const(self, e: ir.Const) -> Compiled:
        value = e.value
        if is_number(value):
            value = float(value)
        return constant(value)

    def _c_VectorExpr(self, e: ir.VectorExpr) -> Compiled:
        parts = [self.compile(c) for c in (e.x, e.y, e.z)]
        span = e.span
        if all(p.const for p in parts):
            return constant(np.array([as_number(p.value, "a vector component", span) for p in parts]))
        fx, fy, fz = (p.fn for p in parts)

        def vector(ctx: SceneContext) -> np.ndarray:
            x, y, z = fx(ctx), fy(ctx), fz(ctx)
            if not (is_number(x) and is_number(y) and is_number(z)):
                raise error_at("vector components must be numbers", span)
            return np.array((x, y, z), dtype=float)

        return Compiled(vector, False)

    def _c_ListExpr(self, e: ir.ListExpr) -> Compiled:
        items = [self.compile(i) for i in e.items]
        if all(i.const for i in items):
            return constant(tuple(i.value for i in items))
        fns = [i.fn for i in items]
        return Compiled(lambda ctx: tuple(f(ctx) for f in fns), False)

    def _c_ObjectRef(self, e: ir.ObjectRef) -> Compiled:
        name, span = e.name, e.span

        def obj(ctx: SceneContext) -> ObjectValue:
            value = ctx.objects.get(name)
            if value is None:
                raise error_at(f"object {name} is not placed yet here", span)
            return value

        # An object whose geometry is known at compile time is a constant for folding
        # (its stand-in carries position, rotation and size); at run time the closure
        # still returns the scene's own object, whose geometry is the same.
        stand_in = self.facts.objects.get(name)
        return Compiled(obj, stand_in is not None, stand_in)

    def _c_VarRef(self, e: ir.VarRef) -> Compiled:
        name = e.name
        compiled = self._var_compiled.get(name)
        if compiled is None:
            var = self._variables.get(name)
            if var is None:
                raise PrscError(f"unknown variable {name!r}", e.span)
            if name in self._var_busy:
                raise PrscError(f"variable {name!r} is defined in terms of itself", e.span)
            self._var_busy.add(name)
            try:
                inner = self.compile(var.value)
            finally:
                self._var_busy.discard(name)
            if inner.const:
                compiled = inner
            else:
                # A random variable is drawn once per scene, however many places read it.
                compiled = Compiled(_once_per_scene(inner.fn, name, _VARIABLES, SceneContext.remember_variable), False)
            self._var_compiled[name] = compiled
        return compiled

    def _c_PropertyRef(self, e: ir.PropertyRef) -> Compiled:
        prop, span = e.prop, e.span
        if isinstance(e.target, ir.ObjectRef):
            known = self.facts.prop(e.target.name, prop)
            if known is not _MISSING:
                return constant(known)
        target = self.compile(e.target)
        if target.const and not isinstance(target.value, ObjectValue):
            return constant(attribute(target.value, prop, None, span))
        tf = target.fn
        return Compiled(lambda ctx: attribute(tf(ctx), prop, ctx, span), False)

    def _c_SelfRef(self, e: SelfRef) -> Compiled:
        raise PrscError("'self' outside a class default", e.span)

    def _c_FacePoint(self, e: ir.FacePoint) -> Compiled:
        words, span = e.words, e.span
        if isinstance(e.target, ir.ObjectRef):
            name = e.target.name
            pos = self.facts.prop(name, "position")
            rot = self.facts.prop(name, "orientation")
            dims = [self.facts.prop(name, d) for d in ("width", "length", "height")]
            if pos is not _MISSING and rot is not _MISSING and all(d is not _MISSING for d in dims):
                stand_in = ObjectValue(name, "", span, pos, rot, tuple(float(d) for d in dims))
                return constant(face_point(stand_in, words, span))
        tf = self.compile(e.target).fn
        return Compiled(lambda ctx: face_point(tf(ctx), words, span), False)

    def _pair(self, left: ir.Expr, right: ir.Expr, apply: Callable[[Any, Any], Any]) -> Compiled:
        """`apply` over two compiled operands, folded to a constant when both are."""
        lc, rc = self.compile(left), self.compile(right)
        if lc.const and rc.const:
            return constant(apply(lc.value, rc.value))
        lf, rf = lc.fn, rc.fn
        return Compiled(lambda ctx: apply(lf(ctx), rf(ctx)), False)

    def _c_RelativeTo(self, e: ir.RelativeTo) -> Compiled:
        span = e.span
        return self._pair(e.value, e.frame, lambda v, f: relative_to(v, f, span))

    def _c_Distance(self, e: ir.Distance) -> Compiled:
        span = e.span
        return self._pair(e.source, e.target, lambda s, t: distance(s, t, span))

    def _c_BinOp(self, e: ir.BinOp) -> Compiled:
        op, span = e.op, e.span
        return self._pair(e.left, e.right, lambda a, b: binary(op, a, b, span))

    def _c_UnaryOp(self, e: ir.UnaryOp) -> Compiled:
        operand, op, span = self.compile(e.operand), e.op, e.span

        def unary(v: Any) -> Any:
            if op == "not":
                return not truthy(v, span)
            v = arith_operand(v)
            if not (is_number(v) or is_vector(v)):
                raise error_at(f"cannot apply unary {op!r} to {describe(v)}", span)
            return -v if op == "-" else v

        if operand.const:
            return constant(unary(operand.value))
        f = operand.fn
        return Compiled(lambda ctx: unary(f(ctx)), False)

    def _c_Compare(self, e: ir.Compare) -> Compiled:
        left, right, op, span = self.compile(e.left), self.compile(e.right), e.op, e.span
        if left.const and right.const:
            return constant(compare(op, left.value, right.value, span))
        lf, rf = left.fn, right.fn
        return Compiled(lambda ctx: compare(op, lf(ctx), rf(ctx), span), False)

    def _c_BoolOp(self, e: ir.BoolOp) -> Compiled:
        operands = [self.compile(o) for o in e.operands]
        is_and, span = e.op == "and", e.span
        if all(o.const for o in operands):
            values = [truthy(o.value, span) for o in operands]
            return constant(all(values) if is_and else any(values))
        fns = [o.fn for o in operands]
        if is_and:
            return Compiled(lambda ctx: all(truthy(f(ctx), span) for f in fns), False)
        return Compiled(lambda ctx: any(truthy(f(ctx), span) for f in fns), False)

    def _c_Call(self, e: ir.Call) -> Compiled:
        func = _MATH.get(e.func)
        span = e.span
        if func is None:
            raise PrscError(f"unknown function {e.func!r}", span)
        args = [self.compile(a) for a in e.args]

        def call(values: list[Any]) -> float:
            nums = [as_number(v, f"an argument of {e.func}", span) for v in values]
            try:
                result = float(func(*nums))
            except (ValueError, TypeError, OverflowError) as error:
                raise error_at(f"{e.func}: {error}", span) from error
            return finite(result, span)

        if all(a.const for a in args):
            return constant(call([a.value for a in args]))
        fns = [a.fn for a in args]
        return Compiled(lambda ctx: call([f(ctx) for f in fns]), False)

    def _c_Distribution(self, e: ir.Distribution) -> Compiled:
        args = [self.compile(a) for a in e.args]
        weights = [self.compile(w) for w in e.weights]
        draw = sampler_for(e, [a.fn for a in args], [w.fn for w in weights])
        return Compiled(_once_per_scene(draw, e.draw_id, _DRAWS, SceneContext.remember_draw), False)

    def _c_SurfaceRef(self, e: ir.SurfaceRef) -> Compiled:
        target, index, name, span = self.compile(e.target), self.compile(e.index), e.name, e.span
        if target.const and index.const:
            return constant(regions.surface(target.value, name, index.value, span))
        tf, xf = target.fn, index.fn
        return Compiled(lambda ctx: regions.surface(tf(ctx), name, xf(ctx), span), False)

    def _c_LinkRef(self, e: ir.LinkRef) -> Compiled:
        from prsc.geometry.link_surfaces import link_surfaces
        from prsc.ir.format import format_expr

        if e.link is None:
            raise PrscError(f"{format_expr(e)}: the link was not read from its file", e.span)
        target, span, chain, offset = self.compile(e.target), e.span, e.link, e.root_offset
        surfaces, label = link_surfaces(chain.boxes), format_expr(e)
        tf = target.fn
        return Compiled(lambda ctx: regions.link(tf(ctx), label, chain, surfaces, offset, ctx, span), False)

    def _c_RegionExpr(self, e: ir.RegionExpr) -> Compiled:
        names = [name for name, _ in e.args]
        args = [self.compile(a) for _, a in e.args]
        kind, span = e.kind, e.span

        def build(values: list[Any]) -> RegionValue:
            a = dict(zip(names, values))
            if kind == "cuboid":
                return regions.cuboid(a["position"], a["orientation"], a["width"], a["length"], a["height"], span)
            if kind == "rectangle":
                return regions.rectangle(a["position"], a["orientation"], a["width"], a["length"], span)
            if kind == "halfspace":
                return regions.halfspace(a["point"], a["normal"], a.get("dist", 0.0), span)
            if kind == "polygon":
                return regions.polygon(a["vertices"], span)
            if kind == "polyhedron":
                return regions.polyhedron(a["vertices"], span)
            if kind == "intersection":
                return regions.intersection(a["regions"], span)
            if kind == "all":
                return regions.everything()
            if kind == "empty":
                return regions.empty()
            raise error_at(f"unknown region kind {kind!r}", span)

        if all(a.const for a in args):
            return constant(build([a.value for a in args]))
        fns = [a.fn for a in args]
        return Compiled(lambda ctx: build([f(ctx) for f in fns]), False)
