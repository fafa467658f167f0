"""Lower the typed IR (prsc.ir.model.Program) to the constraint IR (model.py).

Per object, in dependency order: compile its properties, its orientation rule
(orientation.py) and one position rule per specifier (position.py), plus the workspace
and every `require` linear in its position that mentions no later object
(requirements.py). A rule whose arguments are constant has its rows built once here; an
empty intersection of such rows is reported now, naming an irreducible infeasible subset
of the specifiers with their source lines (diagnostics.py).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from prsc.constraints.analysis import pinned_point, region_rules
from prsc.constraints.containers import containers_rested_in
from prsc.constraints.diagnostics import explain_empty, numeric_failure
from prsc.constraints.evaluate import Fn
from prsc.constraints.polytope_ir import EXCLUSION_KINDS, REQUIRE, ConstraintProgram, ObjectPlan, RequireCheck, Rule
from prsc.constraints.orientation import orientation_rule
from prsc.constraints.build import reads_support
from prsc.constraints.position import specifier_rules, workspace_rule
from prsc.user_assets.asset_links import check_link_target
from prsc.constraints.requirements import RequirePlan, implied_rule, plan_requires, require_check, require_rule
from prsc.constraints.state import LoweringState
from prsc.constraints.support import Support
from prsc.constraints.values import DIMENSIONS, ObjectValue, RegionValue, dimension, static_dims
from prsc.errors import PrscError
from prsc.geometry.exceptions import GeometryError
from prsc.geometry.iis import is_feasible
from prsc.geometry.lp import solve_lp
from prsc.geometry.polytope import Polytope
from prsc.ir import model as ir
from prsc.ir.format import format_expr
from prsc.ir.program import ObjectDecl, Program


# Why an excluded cell needs the rotation first: with the rotation decided after the position
# the cell could only be bounded, and subtracting a bound either keeps boxes wholly in view
# or drops positions that are not (docs/language.md, "`visible from C`").
_ROTATION_FIRST = ("`not visible from C` needs {name}'s rotation before its position, and `facing toward` "
                   "sets it after: give a yaw instead, e.g. `facing (0, 360 deg)`")


def _bounding_box(poly: Polytope) -> Polytope | None:
    """The axis-aligned bounding box of a region (6 LPs), or None if it is unbounded or empty."""
    lo, hi = np.zeros(3), np.zeros(3)
    for axis in range(3):
        for sign in (1.0, -1.0):
            cost = np.zeros(3)
            cost[axis] = sign
            sol = solve_lp(cost, np.vstack([poly.A, poly.C]), np.concatenate([np.full(len(poly.b), -np.inf), poly.d]), np.concatenate([poly.b, poly.d]))
            if sol.status != "optimal":
                return None
            if sign > 0:
                lo[axis] = sol.x[axis]
            else:
                hi[axis] = sol.x[axis]
    eye = np.eye(3)
    return Polytope.from_rows(np.vstack([eye, -eye]), np.concatenate([hi, -lo]))


def _properties(low: LoweringState, obj: ObjectDecl) -> tuple[dict[str, Fn], dict[str, Any]]:
    """The object's property evaluators, and the values known at compile time."""
    known = low.facts.props[obj.name] = {}
    property_fns: dict[str, Fn] = {}
    for prop, expr in obj.properties:
        compiled = low.compiler.compile(expr)
        property_fns[prop] = compiled.fn
        if compiled.const:
            known[prop] = compiled.value
    for dim in DIMENSIONS:
        if dim not in property_fns:
            property_fns[dim] = lambda ctx: 1.0
            known[dim] = 1.0
    for dim in DIMENSIONS:
        if dim in known:
            expr = obj.prop(dim)
            dimension(known[dim], dim, obj.name, expr.span if expr is not None else obj.span)
    return property_fns, dict(known)


def _check_link_targets(obj: ObjectDecl) -> None:
    """`on`/`in` a link whose geometry has no such surface: an error before any scene (the link's
    boxes are in its own frame, whatever its pose)."""
    for spec in obj.specifiers:
        target = spec.region if isinstance(spec, ir.In) else getattr(spec, "target", None)
        if isinstance(target, ir.LinkRef) and target.link is not None and isinstance(spec, (ir.In, ir.On)):
            check_link_target(format_expr(target), target.link, isinstance(spec, ir.In), spec.completely, spec.span)


def _lower_object(low: LoweringState, obj: ObjectDecl, requires: RequirePlan) -> ObjectPlan:
    name = obj.name
    facts = low.facts
    property_fns, static_props = _properties(low, obj)
    dims = static_dims(static_props)
    orientation = orientation_rule(low, obj)
    rotation = np.eye(3) if orientation is None else orientation.static_value
    after = orientation is not None and orientation.after_position
    support: Support | None = None
    if dims is not None and rotation is not None:
        support = Support(rotation, np.array(dims) * 0.5, "exact")
    elif dims is not None and after:
        support = Support(None, np.array(dims) * 0.5, orientation.bound_mode)  # type: ignore[union-attr]
    me = ObjectValue(name, obj.class_name, obj.span, None, rotation, dims, dict(static_props))

    rests_in = containers_rested_in(low, obj)  # first: it refuses a container interior that varies
    _check_link_targets(obj)
    rules: list[Rule] = []
    exclusions: list[Rule] = []
    for spec in obj.specifiers:
        for rule in specifier_rules(low, obj, spec, support, me):
            if rule.kind not in EXCLUSION_KINDS:
                rules.append(rule)
                continue
            if after and reads_support(rule):  # its cell is eroded by the object's rotated box
                raise PrscError(_ROTATION_FIRST.format(name=name), spec.span)
            exclusions.append(rule)
    if low.program.workspace is not None:
        rules.append(workspace_rule(low, obj, low.program.workspace, support, me))
    checks: list[RequireCheck] = []
    for k, req in requires.per_object[name]:
        label, soft = requires.labels[k], requires.soft_index.get(k)
        lowered = require_rule(low, me, req, label, soft, support is not None and rotation is not None) if not after else None
        if lowered is not None:
            rules.append(lowered)
        else:
            checks.append(require_check(low, req, label, soft))
            implied = implied_rule(low, me, req, label, soft, support is not None and rotation is not None) if not after else None
            if implied is not None:
                rules.append(implied)

    region = region_rules(rules)
    if region.static_rows is not None and not is_feasible(region.static_rows):
        raise explain_empty(low.labels, region.static_rows, name, obj.span, "infeasible specification", low.declarations)
    static_position = None if region.static_rows is None else pinned_point(region.static_rows)
    if static_position is not None:
        facts.positions[name] = static_position
        if rotation is not None and dims is not None:
            facts.objects[name] = ObjectValue(name, obj.class_name, obj.span, static_position, rotation, dims, dict(static_props))
    if rotation is not None:
        facts.rotations[name] = rotation
    return ObjectPlan(
        index=low.index_of[name],
        name=name,
        class_name=obj.class_name,
        anonymous=obj.anonymous,
        span=obj.span,
        property_fns=property_fns,
        static_props=static_props,
        orientation=orientation,
        region=region,
        checks=tuple(checks),
        depends_on=tuple(obj.depends_on),
        static_position=static_position,
        static_support=support,
        rests_in=rests_in,
        exclusions=tuple(exclusions),
    )


def lower_program(program: Program) -> ConstraintProgram:
    """Lower a typed Program to the constraint IR; PrscError for a provably empty region."""
    low = LoweringState(program)
    workspace_box = None
    if program.workspace is not None:
        compiled = low.compiler.compile(program.workspace)
        if compiled.const and isinstance(compiled.value, RegionValue):
            workspace_box = _bounding_box(compiled.value.poly)
    requires = plan_requires(low)
    plans = []
    for obj in program.objects:
        try:
            plans.append(_lower_object(low, obj, requires))
        except GeometryError as error:
            raise numeric_failure(obj.name, obj.span, error) from error

    scene_checks = []
    require_tests = []
    for k, req in enumerate(program.requires):
        check = require_check(low, req, requires.labels[k], requires.soft_index.get(k))
        require_tests.append((requires.last[k], check))
        if requires.last[k] < 0:
            scene_checks.append(check)
    params = tuple((p.name, low.compiler.compile(p.value).fn) for p in program.params)
    lowered = {}
    for plan in plans:
        ids = tuple(r.label_id for r in plan.rules if r.kind == REQUIRE)
        if ids:
            lowered[plan.name] = ids
    return ConstraintProgram(
        program=program,
        objects=tuple(plans),
        labels=tuple(low.labels),
        scene_checks=tuple(scene_checks),
        soft_requires=requires.soft,
        params=params,
        require_tests=tuple(require_tests),
        lowered_requires=lowered,
        workspace_box=workspace_box,
    )


__all__ = ["lower_program"]
