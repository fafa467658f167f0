"""Vector, distribution and region constructors: argument checking and normalisation."""

from __future__ import annotations

from typing import Protocol

from prsc.errors import PrscError
from prsc.ir import model as ir
from prsc.ir.type_checks import POINT_TYPES, article, expect
from prsc.syntax import nodes


class DrawCounter(Protocol):
    def take(self) -> int: ...


class ExprResolver(Protocol):
    """What a constructor needs of the expression resolver (expressions.py), which calls it:
    named here as an interface so that this module sits below expressions.py."""

    draws: DrawCounter

    def resolve(self, e: nodes.Expr) -> ir.Expr: ...

T = ir.Type
NUMBER = {T.SCALAR}
REGION_FORMS = {
    "Cuboid": "Cuboid(position, orientation, width, length, height) or Cuboid(origin, orientation, dims)",
    "Rectangle3D": "Rectangle3D(width, length, origin, orientation)",
    "Rect3D": "Rect3D(origin, orientation, dims)",
    "HalfSpace": "HalfSpace(point, normal[, dist])",
    "Halfspace": "Halfspace(origin, normal[, dist])",
    "ConvexPolygon3D": "ConvexPolygon3D([v1, v2, v3, ...])",
    "ConvexPolyhedron": "ConvexPolyhedron([v1, v2, v3, v4, ...])",
    "Intersection": "Intersection(r1, r2, ...)",
    "All": "All()",
    "Empty": "Empty()",
}


def _arity_error(name: str, form: str, call: nodes.Call) -> PrscError:
    return PrscError(f"wrong number of arguments to {name} ({len(call.args)}): write {form}", call.span)


def _component(dims: ir.Expr, axis: str) -> ir.Expr:
    """One component of a dimensions vector (directly when it is written out)."""
    if isinstance(dims, ir.VectorExpr):
        return getattr(dims, axis)
    return ir.PropertyRef(dims.span, T.SCALAR, dims, axis)


def construct(resolver: ExprResolver, name: str, call: nodes.Call) -> ir.Expr:
    """The IR of a constructor call `name(args)`."""
    args = [resolver.resolve(a) for a in call.args] if name not in ("Discrete", "Options") else None
    if name in ("Vector3D", "V3D"):
        if len(call.args) != 3:
            raise _arity_error(name, f"{name}(x, y, z)", call)
        x, y, z = (expect(a, NUMBER, f"each coordinate of {name}") for a in args)
        return ir.VectorExpr(call.span, T.VECTOR, x, y, z)
    if name in ("Range", "Normal", "TruncatedNormal"):
        kind, arity, form = {
            "Range": ("range", 2, "Range(low, high)"),
            "Normal": ("normal", 2, "Normal(mean, sd)"),
            "TruncatedNormal": ("truncnormal", 4, "TruncatedNormal(mean, sd, low, high)"),
        }[name]
        if len(args) != arity:
            raise _arity_error(name, form, call)
        args = [expect(a, NUMBER, f"each argument of {name}") for a in args]
        return ir.Distribution(call.span, T.SCALAR, kind, tuple(args), resolver.draws.take())
    if name == "Uniform":
        if not args:
            raise _arity_error(name, "Uniform(v1, v2, ...)", call)
        return _choice(resolver, call, tuple(args), ())
    if name in ("Options", "Discrete"):
        return _options(resolver, name, call)
    return _region(resolver, name, call, args)


def _choice(resolver: ExprResolver, call: nodes.Call, options: tuple[ir.Expr, ...],
            weights: tuple[ir.Expr, ...]) -> ir.Expr:
    types = {o.type for o in options}
    value_type = types.pop() if len(types) == 1 else T.ANY
    kind = "discrete" if weights else "uniform"
    return ir.Distribution(call.span, value_type, kind, options, resolver.draws.take(), weights)


def _options(resolver: ExprResolver, name: str, call: nodes.Call) -> ir.Expr:
    if len(call.args) != 1 or not isinstance(call.args[0], (nodes.ListLit, nodes.DictLit)):
        raise _arity_error(name, f"{name}([v1, v2, ...])" if name == "Options" else "Discrete({v1: w1, ...})", call)
    arg = call.args[0]
    if isinstance(arg, nodes.ListLit):
        if name == "Discrete":
            raise PrscError("Discrete takes a {value: weight, ...} mapping", arg.span)
        if not arg.items:
            raise PrscError(f"{name} needs at least one value", arg.span)
        return _choice(resolver, call, tuple(resolver.resolve(i) for i in arg.items), ())
    if not arg.items:
        raise PrscError(f"{name} needs at least one value", arg.span)
    options = tuple(resolver.resolve(k) for k, _ in arg.items)
    weights = []
    for _, w in arg.items:
        weight = expect(resolver.resolve(w), NUMBER, "a weight")
        if isinstance(weight, ir.Const) and float(weight.value) < 0:
            raise PrscError("a weight cannot be negative", weight.span)
        weights.append(weight)
    return _choice(resolver, call, options, tuple(weights))


def _region(resolver: ExprResolver, name: str, call: nodes.Call, args: list[ir.Expr]) -> ir.Expr:
    form = REGION_FORMS[name]
    n = len(args)
    span = call.span

    def point(a: ir.Expr, what: str) -> ir.Expr:
        return expect(a, POINT_TYPES, f"the {what} of {name}")

    def number(a: ir.Expr, what: str) -> ir.Expr:
        return expect(a, NUMBER, f"the {what} of {name}")

    if name == "Cuboid":
        if n == 5:
            pos, ori, w, l, h = args
            named = (("position", point(pos, "position")), ("orientation", point(ori, "orientation")),
                     ("width", number(w, "width")), ("length", number(l, "length")), ("height", number(h, "height")))
        elif n == 3:
            pos, ori, dims = args
            dims = expect(dims, {T.VECTOR}, f"the dims of {name}")
            named = (("position", point(pos, "origin")), ("orientation", point(ori, "orientation")),
                     ("width", _component(dims, "x")), ("length", _component(dims, "y")),
                     ("height", _component(dims, "z")))
        else:
            raise _arity_error(name, form, call)
        return ir.RegionExpr(span, T.REGION, "cuboid", named)
    if name == "Rectangle3D":
        if n != 4:
            raise _arity_error(name, form, call)
        w, l, pos, ori = args
        named = (("position", point(pos, "origin")), ("orientation", point(ori, "orientation")),
                 ("width", number(w, "width")), ("length", number(l, "length")))
        return ir.RegionExpr(span, T.REGION, "rectangle", named)
    if name == "Rect3D":
        if n != 3:
            raise _arity_error(name, form, call)
        pos, ori, dims = args
        dims = expect(dims, {T.VECTOR}, f"the dims of {name}")
        named = (("position", point(pos, "origin")), ("orientation", point(ori, "orientation")),
                 ("width", _component(dims, "x")), ("length", _component(dims, "y")))
        return ir.RegionExpr(span, T.REGION, "rectangle", named)
    if name in ("HalfSpace", "Halfspace"):
        if n not in (2, 3):
            raise _arity_error(name, form, call)
        dist = number(args[2], "distance") if n == 3 else ir.Const(span, T.SCALAR, 0.0)
        named = (("point", point(args[0], "point")), ("normal", expect(args[1], {T.VECTOR}, f"the normal of {name}")),
                 ("dist", dist))
        return ir.RegionExpr(span, T.REGION, "halfspace", named)
    if name in ("ConvexPolygon3D", "ConvexPolyhedron"):
        least = 3 if name == "ConvexPolygon3D" else 4
        if n != 1 or not isinstance(args[0], ir.ListExpr):
            raise _arity_error(name, form, call)
        vertices = args[0]
        for v in vertices.items:
            expect(v, POINT_TYPES, f"each vertex of {name}")
        if len(vertices.items) < least:
            raise PrscError(f"{name} needs at least {least} vertices, got {len(vertices.items)}", vertices.span)
        kind = "polygon" if name == "ConvexPolygon3D" else "polyhedron"
        return ir.RegionExpr(span, T.REGION, kind, (("vertices", vertices),))
    if name == "Intersection":
        if n == 0:
            raise _arity_error(name, form, call)
        for r in args:
            if r.type not in (T.REGION, T.ANY):
                raise PrscError(f"each argument of Intersection must be a region, not {article(r.type)}", r.span)
        return ir.RegionExpr(span, T.REGION, "intersection", (("regions", ir.ListExpr(span, T.LIST, tuple(args))),))
    if name in ("All", "Empty"):
        if n:
            raise _arity_error(name, form, call)
        return ir.RegionExpr(span, T.REGION, name.lower(), ())
    raise PrscError(f"unknown constructor {name}", span)  # pragma: no cover
