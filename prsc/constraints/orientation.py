"""Orientation specifiers lowered to rule records, and the rotation each gives."""

from __future__ import annotations

from typing import Any

import numpy as np

from prsc.constraints.context import SceneContext
from prsc.constraints.polytope_ir import POSITION, OrientationRule
from prsc.constraints.regions import rotation_of
from prsc.constraints.state import LoweringState
from prsc.constraints.values import ObjectValue, OrientedPoint, as_position
from prsc.errors import PrscError
from prsc.geometry.rotations import rotation_taking_y_to, yaw_matrix, yaw_toward
from prsc.ir import model as ir
from prsc.ir.program import ObjectDecl


def orientation_rule(low: LoweringState, obj: ObjectDecl) -> OrientationRule | None:
    """The object's orientation rule (the last specifier setting orientation wins)."""
    spec = None
    for s in obj.specifiers:
        if "orientation" in s.sets:
            spec = s
    if spec is None:
        return None
    label = low.label(obj.name, low.text(spec.span, type(spec).__name__.lower()), spec.span, POSITION)
    if isinstance(spec, ir.FacingToward):
        kind, arg = "facing toward", spec.target
    elif isinstance(spec, ir.Facing):
        kind, arg = "facing", spec.direction
    elif isinstance(spec, ir.With):
        kind, arg = "with orientation", spec.value
    else:
        raise PrscError(f"unsupported orientation specifier {type(spec).__name__}", spec.span)
    after = "position" in spec.reads or kind == "facing toward"
    compiled = low.compiler.compile(arg)
    rule = OrientationRule(kind, label, arg, after, "yaw" if kind == "facing toward" else ("free" if after else "exact"), compiled.fn)
    if compiled.const and not after:
        static = rotation_from(rule, compiled.value)
        return OrientationRule(rule.kind, label, arg, False, "exact", compiled.fn, static)
    return rule


def rotation_from(rule: OrientationRule, value: Any, me: ObjectValue | None = None) -> np.ndarray:
    """The rotation a rule gives for its argument's value (and, for `facing toward`, the object's position)."""
    span = rule.arg.span
    if rule.kind == "facing toward":
        goal = as_position(value)
        if goal is None:
            raise PrscError("'facing toward' needs an object or a point", span)
        assert me is not None and me.position is not None
        direction = goal - me.position
        if float(np.hypot(direction[0], direction[1])) == 0.0:
            return np.eye(3)  # straight above or below: every yaw faces it
        return yaw_matrix(yaw_toward(direction))
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return yaw_matrix(float(value))
    if rule.kind == "with orientation":
        return rotation_of(value, span)
    if isinstance(value, OrientedPoint):
        return value.rotation
    pos = as_position(value)
    if pos is None:
        raise PrscError("'facing' needs a vector or an angle", span)
    try:
        return rotation_taking_y_to(pos)
    except ValueError as error:
        raise PrscError(f"'facing': {error}", span) from error


def orientation_of(rule: OrientationRule, ctx: SceneContext, me: ObjectValue) -> np.ndarray:
    """The object's rotation in one scene."""
    if rule.static_value is not None:
        return rule.static_value
    return rotation_from(rule, rule.value(ctx), me)
