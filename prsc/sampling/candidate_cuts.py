"""The rules that cut a rectangle's polygon in candidate rounds (candidate_regions.py), as rows
a.p <= b per candidate on its own centre: a direction (`left of tray by 0.05`), `visible from
C` (C's frustum), or rows fixed for every scene; and those fixed rows too many to cut, which
are tested per candidate instead (a reach ring's)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from prsc.constraints.polytope_ir import Rule
from prsc.constraints.specifier_rows import DIRECTION_AXES
from prsc.constraints.values import ObjectValue
from prsc.constraints.visibility import camera_frustum
from prsc.errors import PrscError
from prsc.ir import model as ir
from prsc.ir.models import model_of
from prsc.sampling.batch_values import Unbatchable
from prsc.sampling.candidate_rules import support
from prsc.sampling.candidate_values import CandidateCompiler, CandidateState
from prsc.sampling.runtime import ObjectRuntime

# Rows a.p <= b of each candidate on its own centre: (a (n, m, 3), b (n, m)).
Cut = Callable[[CandidateState], tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class Placed:
    """What the plan knows of the objects before the one being planned."""

    runtimes: dict[str, ObjectRuntime]
    bounds: dict[str, tuple[np.ndarray, np.ndarray]]  # bounds of the centre in every candidate
    reaches: dict[str, float]  # bound of the box's half diagonal


MAX_CUT_ROWS = 16
"""Rows a polygon is cut by at most: its vertices are the crossings of every pair of its rows,
per candidate (a reach ring's hundred rows would be 10,000 crossings for each)."""


def tested_not_cut(rule: Rule) -> bool:
    """Whether a rule of a rectangle's object is tested per candidate (`inside_test`) rather than
    cut into its polygon: rows fixed for every scene, more than MAX_CUT_ROWS of them."""
    return rule.template is not None and len(rule.template.rows.b) > MAX_CUT_ROWS


def rows_test(a: np.ndarray, b: np.ndarray, name: str, anchor: str | None = None):
    """Rows a.p <= b (moved with `anchor`'s centre when carried) on each candidate's centre, as a test."""
    def inside(state: CandidateState) -> np.ndarray:
        shift = 0.0 if anchor is None else state.positions[anchor] @ a.T
        return np.all(state.positions[name] @ a.T <= b + shift + 1e-9, axis=1)

    return inside


def inside_test(rule: Rule, rt: ObjectRuntime, placed: Placed):
    """A rule's fixed rows (those `rule_cut` would cut with) as a test of each candidate's centre."""
    found = _template_rows(rule, rt, placed)
    if found is None:
        raise Unbatchable(f"{rt.plan.name}'s `{rule.kind}` rows are carried by an object of random size or rotation")
    rows, anchor = found
    return rows_test(rows.A, rows.b, rt.plan.name, anchor)


def _template_rows(rule: Rule, rt: ObjectRuntime, placed: Placed):
    """(rows, anchor) of a rule the compiler fixed for every scene (a static template, or one carried
    by an anchor for an object of fixed size and rotation); None for other rules."""
    template = rule.template
    if template is None or (template.anchor is not None and rt.support is None):
        return None
    if len(template.rows.d) or (template.anchor is not None and template.anchor not in placed.runtimes):
        raise Unbatchable(f"{rt.plan.name}'s `{rule.kind}` rows are equalities or carried by a later object")
    return template.rows, template.anchor


def rule_cut(rule: Rule, rt: ObjectRuntime, placed: Placed, compiler: CandidateCompiler) -> Cut:
    """A rule that cuts the rectangle, as rows per candidate: a direction (specifiers.rows_direction),
    or rows the compiler fixed for every scene (a static template, or one carried by an anchor for
    an object of fixed size and rotation)."""
    me = rt.plan.name
    found = _template_rows(rule, rt, placed)
    if found is not None:
        a, b, anchor = found[0].A, found[0].b, found[1]

        def fixed(state: CandidateState) -> tuple[np.ndarray, np.ndarray]:
            n = len(state.keys)
            shift = 0.0 if anchor is None else state.positions[anchor] @ a.T
            return np.broadcast_to(a, (n,) + a.shape), np.broadcast_to(b + shift, (n, len(b)))

        return fixed
    if rule.kind == "visible":
        return _visible(rule, me, placed)
    if rule.kind != "direction":
        raise Unbatchable(f"{me}'s `{rule.kind}` rule")
    target = rule.args[0]
    if not isinstance(target, ir.ObjectRef) or target.name not in placed.runtimes:
        raise Unbatchable(f"{me} is placed relative to something other than an object placed before it")
    by = compiler.compile(rule.args[1]) if len(rule.args) > 1 else None
    up_to = compiler.compile(rule.args[2]) if len(rule.args) > 2 else None
    if any(v is not None and v.vector for v in (by, up_to)):
        raise Unbatchable(f"{me}'s distance from {target.name} is a vector")
    if by is not None and up_to is not None and not up_to.lo[0] > by.hi[0]:
        raise Unbatchable(f"{me}'s band beside {target.name} may be a line")  # a segment, not a polygon
    axis, other = DIRECTION_AXES[rule.option("relation")], target.name

    def direction(state: CandidateState) -> tuple[np.ndarray, np.ndarray]:
        # n.(p - X) >= d + s(n), and <= e + s(n) with `by (d, e)`.
        n = state.rotations[other] @ axis
        base = np.einsum("ni,ni->n", n, state.positions[other]) \
            + support(n[:, None, :], state.rotations[me], state.dims[me] * 0.5)[:, 0]
        low = base if by is None else base + by.fn(state)[:, 0]
        if up_to is None:
            return -n[:, None, :], -low[:, None]
        return np.stack([-n, n], axis=1), np.stack([-low, base + up_to.fn(state)[:, 0]], axis=1)

    return direction


def _visible(rule: Rule, me: str, placed: Placed) -> Cut:
    """`visible from C`: a.p <= b - s(a) for the six planes of C's frustum, placed where C is in each
    candidate (visibility.rows_visible); C's size and camera properties are the same in every scene."""
    target = rule.args[0]
    if not isinstance(target, ir.ObjectRef) or target.name not in placed.runtimes:
        raise Unbatchable(f"{me} is visible from something other than an object placed before it")
    camera = placed.runtimes[target.name]
    plan = camera.plan
    if camera.dims is None or set(plan.property_fns) - set(plan.static_props):
        raise Unbatchable(f"{plan.name}'s size or camera properties change between scenes")
    value = ObjectValue(plan.name, plan.class_name, plan.span, None, None, camera.dims, dict(plan.static_props), plan.property_fns)
    if not (value.props.get("camera") or model_of(value.props, value.class_name) == "camera"):
        raise Unbatchable(f"{plan.name} is no camera")  # the scalar sampler explains it
    try:
        a_local, b_local = camera_frustum(value, plan.span).local_rows()
    except PrscError:
        raise Unbatchable(f"{plan.name}'s frustum is not valid") from None
    name = plan.name

    def visible(state: CandidateState) -> tuple[np.ndarray, np.ndarray]:
        a = np.einsum("mj,nij->nmi", a_local, state.rotations[name])  # a R^T per candidate (Frustum.world_rows)
        b = b_local + np.einsum("nmi,ni->nm", a, state.positions[name])
        return a, b - support(a, state.rotations[me], state.dims[me] * 0.5)

    return visible
