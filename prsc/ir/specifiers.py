"""AST specifiers -> IR specifiers: argument types, what each sets and reads."""

from __future__ import annotations

import dataclasses

from prsc.errors import PrscError
from prsc.ir import model as ir
from prsc.ir.builtins import AXES, BOX_READS, DIRECTION_PHRASES, joint_property
from prsc.ir.expressions import ExprResolver
from prsc.ir.type_checks import LOCATED_TYPES, POINT_TYPES, article, expect, type_words
from prsc.ir.scope import ClassInfo, VariableInfo, did_you_mean
from prsc.syntax import nodes

T = ir.Type
POSITION = ("position",)
PLANAR_REGIONS = ("rectangle", "polygon")


def _region_kind(resolver: ExprResolver, expr: ir.Expr) -> str | None:
    """The region constructor behind an expression, following variables (None: not known statically)."""
    seen = 0
    while isinstance(expr, ir.VarRef) and seen < 100:
        binding = resolver.scope.variables.get(expr.name)
        if not isinstance(binding, VariableInfo):
            return None
        expr = binding.value
        seen += 1
    return expr.kind if isinstance(expr, ir.RegionExpr) else None


def _number(expr: ir.Expr) -> float | None:
    if isinstance(expr, ir.Const) and isinstance(expr.value, (int, float)) and not isinstance(expr.value, bool):
        return float(expr.value)
    if isinstance(expr, ir.UnaryOp) and expr.op == "-":
        inner = _number(expr.operand)
        return None if inner is None else -inner
    return None


def same_value(a: ir.Expr, b: ir.Expr) -> bool:
    """Whether two expressions denote the same value in every scene: equal apart from spans
    (a variable or a distribution node is one draw per scene), or equal constant vectors."""
    if isinstance(a, ir.VectorExpr) and isinstance(b, ir.VectorExpr):
        parts = [(_number(x), _number(y)) for x, y in ((a.x, b.x), (a.y, b.y), (a.z, b.z))]
        if all(x is not None and x == y for x, y in parts):
            return True
    if type(a) is not type(b):
        return False
    for f in dataclasses.fields(a):
        if f.name == "span":
            continue
        left, right = getattr(a, f.name), getattr(b, f.name)
        if isinstance(left, ir.Expr):
            if not (isinstance(right, ir.Expr) and same_value(left, right)):
                return False
        elif isinstance(left, tuple):
            if not isinstance(right, tuple) or len(left) != len(right):
                return False
            for x, y in zip(left, right):
                if isinstance(x, ir.Expr) != isinstance(y, ir.Expr):
                    return False
                if (isinstance(x, ir.Expr) and not same_value(x, y)) or (not isinstance(x, ir.Expr) and x != y):
                    return False
        elif left != right:
            return False
    return True


def lower_specifier(resolver: ExprResolver, cls: ClassInfo, spec: nodes.Specifier) -> ir.Specifier:
    """The IR of one specifier on an object of class cls."""
    r = resolver.resolve
    span = spec.span
    if isinstance(spec, nodes.WithSpec):
        return _with(resolver, cls, spec)
    if isinstance(spec, nodes.JointSpec):
        return _with_joint(resolver, cls, spec)
    if isinstance(spec, nodes.AtSpec):
        point = expect(r(spec.point), POINT_TYPES, "the point after `at`")
        return ir.At(span, POSITION, (), point)
    if isinstance(spec, nodes.InSpec):
        region = r(spec.region)
        if region.type == T.OBJECT:
            # `in X` for an object: X's container interior, as `on X` rests on its floor
            # (constraints/specifiers.interior_of; an object with no interior is an error there).
            return ir.On(span, POSITION, BOX_READS, region, spec.completely, inside=True)
        if region.type not in (T.REGION, T.ANY):
            raise PrscError(f"`in` needs a region, not {article(region.type)}", region.span)
        reads = BOX_READS if spec.completely else ()
        return ir.In(span, POSITION, reads, region, spec.completely)
    if isinstance(spec, nodes.OnSpec):
        target = r(spec.target)
        word = "completely on" if spec.completely else "on"
        if target.type not in (T.OBJECT, T.REGION, T.VECTOR, T.ORIENTED_POINT, T.ANY):
            raise PrscError(f"`{word}` needs an object, a planar region or a point, not {article(target.type)}",
                            target.span)
        if target.type == T.REGION:
            kind = _region_kind(resolver, target)
            if kind is not None and kind not in PLANAR_REGIONS:
                raise PrscError(f"`{word}` needs a planar region (Rectangle3D, Rect3D, ConvexPolygon3D), "
                                f"not a {kind} region; use `in` for a solid region", target.span)
        return ir.On(span, POSITION, BOX_READS, target, spec.completely)
    if isinstance(spec, nodes.DirectionSpec):
        word = DIRECTION_PHRASES.get(spec.relation, spec.relation)
        target = expect(r(spec.target), LOCATED_TYPES, f"the reference of `{word}`")
        if isinstance(spec.by, nodes.Pair):  # `by (low, high)`: the gap lies in [low, high]
            low = expect(r(spec.by.low), {T.SCALAR}, f"the least gap in `{word} ... by (low, high)`")
            high = expect(r(spec.by.high), {T.SCALAR}, f"the greatest gap in `{word} ... by (low, high)`")
            low_value, high_value = _number(low), _number(high)
            if low_value is not None and high_value is not None and high_value < low_value:
                raise PrscError(f"`{word} X by (low, high)` needs low <= high, not ({low_value:g}, {high_value:g})",
                                spec.by.span)
            return ir.Direction(span, POSITION, BOX_READS, spec.relation, target, low, high)
        by = expect(r(spec.by), {T.SCALAR}, f"the gap after `{word} ... by`") if spec.by is not None else None
        return ir.Direction(span, POSITION, BOX_READS, spec.relation, target, by)
    if isinstance(spec, nodes.BeyondSpec):
        target = expect(r(spec.target), LOCATED_TYPES, "the reference of `beyond`")
        by = expect(r(spec.by), {T.SCALAR, T.VECTOR}, "the amount after `beyond ... by`")
        origin = expect(r(spec.origin), LOCATED_TYPES, "the point after `beyond ... from`")
        if same_value(target, origin):
            raise PrscError("`beyond X by d from P` needs X and P to differ: here both are the same point, "
                            "so there is no direction to go beyond in", span)
        return ir.Beyond(span, POSITION, (), target, by, origin)
    if isinstance(spec, nodes.AlignedSpec):
        axis = spec.axis.lower()
        if axis not in AXES:
            raise PrscError(f"`aligned with` takes the axis x, y or z, not '{spec.axis}'", spec.axis_span)
        target = expect(r(spec.target), LOCATED_TYPES, "the reference of `aligned with`")
        return ir.AlignedWith(span, POSITION, (), target, axis)
    if isinstance(spec, nodes.FacingSpec):
        direction = expect(r(spec.direction), {T.VECTOR, T.SCALAR},
                           "the direction after `facing` (a vector, or a yaw angle)")
        return ir.Facing(span, ("orientation",), (), direction)
    if isinstance(spec, nodes.FacingTowardSpec):
        target = expect(r(spec.target), LOCATED_TYPES, "the target of `facing toward`")
        return ir.FacingToward(span, ("orientation",), POSITION, target)
    if isinstance(spec, nodes.ReachableSpec):
        robot = r(spec.robot)
        if robot.type not in (T.OBJECT, T.ANY):
            raise PrscError(f"`reachable by` needs a robot object, not {article(robot.type)}", robot.span)
        return ir.ReachableBy(span, POSITION, (), robot)
    if isinstance(spec, nodes.StablySpec):
        target = r(spec.target)
        if target.type not in (T.OBJECT, T.REGION, T.ANY):
            raise PrscError(f"`stably on` needs an object or a planar region, not {article(target.type)}", target.span)
        return ir.StablyOn(span, POSITION, BOX_READS, target)
    if isinstance(spec, nodes.VisibleSpec):
        camera = r(spec.camera)
        if camera.type not in (T.OBJECT, T.ANY):
            phrase = "not visible from" if spec.negated else "visible from"
            raise PrscError(f"`{phrase}` needs a camera object, not {article(camera.type)}", camera.span)
        return ir.VisibleFrom(span, POSITION, BOX_READS, camera, outside=spec.negated)
    raise PrscError("unknown specifier", span)  # pragma: no cover


def _with_joint(resolver: ExprResolver, cls: ClassInfo, spec: nodes.JointSpec) -> ir.With:
    """`with joint "NAME" v`: the property `joint_property(NAME)`, a length or an angle
    (whether NAME is a joint of the object's asset is checked with its file, prsc/ir/asset_models.py)."""
    if not spec.joint:
        raise PrscError("a joint name cannot be empty", spec.joint_span)
    value = resolver.resolve(spec.value)
    accepted = cls.accepted_types("width") or (T.SCALAR,)
    if value.type != T.ANY and value.type not in accepted:
        raise PrscError(f"`with joint` needs {type_words(accepted)}, not {article(value.type)}", value.span)
    prop = joint_property(spec.joint)
    return ir.With(spec.span, (prop,), (), prop, value)


def _with(resolver: ExprResolver, cls: ClassInfo, spec: nodes.WithSpec) -> ir.With:
    prop = spec.prop
    accepted = cls.accepted_types(prop)
    if accepted is None:
        raise PrscError(f"unknown property '{prop}' for a {cls.name}{did_you_mean(prop, cls.properties())}",
                        spec.prop_span)
    value = resolver.resolve(spec.value)
    if value.type != T.ANY and value.type not in accepted:
        raise PrscError(f"`with {prop}` needs {type_words(accepted)}, not {article(value.type)}", value.span)
    return ir.With(spec.span, (prop,), (), prop, value)
