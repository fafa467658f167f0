"""`require` lowering: linear conditions become rules on the object placed last, the rest checks."""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from prsc.constraints.analysis import rigid
from prsc.constraints.build import rows_polytope
from prsc.constraints.context import SceneContext
from prsc.constraints.polytope_ir import REQUIRE, RequireCheck, RowLabel, RowTemplate, Rule, SoftRequire
from prsc.constraints.operations import truthy
from prsc.constraints.require_rows import constant_apart_from, implied_condition, lower_condition, mentioned_objects
from prsc.constraints.state import LoweringState
from prsc.constraints.values import ObjectValue
from prsc.errors import PrscError, Span
from prsc.ir.program import Require


@dataclass(frozen=True)
class RequirePlan:
    """Where each require of the program goes: its label, owner object, soft index."""

    labels: dict[int, int]  # require index -> label id
    last: dict[int, int]  # require index -> index of the object placed last among those it mentions (-1: none)
    per_object: dict[str, list[tuple[int, Require]]]
    soft: tuple[SoftRequire, ...]
    soft_index: dict[int, int]


def plan_requires(low: LoweringState) -> RequirePlan:
    """Label every require and assign it to the object placed last among those it mentions."""
    program = low.program
    per_object: dict[str, list[tuple[int, Require]]] = {o.name: [] for o in program.objects}
    soft: list[SoftRequire] = []
    soft_index: dict[int, int] = {}
    labels: dict[int, int] = {}
    last_of: dict[int, int] = {}
    for k, req in enumerate(program.requires):
        names = mentioned_objects(req.condition)
        unknown = sorted(n for n in names if n not in low.index_of)
        if unknown:
            raise PrscError(f"require mentions unknown object {unknown[0]}", req.span)
        if not 0.0 <= req.probability <= 1.0:
            raise PrscError(f"require[p] needs 0 <= p <= 1, got {req.probability}", req.span)
        last = max((low.index_of[n] for n in names), default=-1)
        owner = program.objects[last].name if last >= 0 else ""
        refs = tuple(sorted(n for n in names if n != owner))
        labels[k] = len(low.labels)
        low.labels.append(RowLabel(owner, "require " + low.text(req.condition.span, "condition"), req.span, REQUIRE, refs))
        if req.probability < 1.0:
            soft_index[k] = len(soft)
            soft.append(SoftRequire(len(soft), req.probability, labels[k]))
        last_of[k] = last
        if last >= 0:
            per_object[owner].append((k, req))
    return RequirePlan(labels, last_of, per_object, tuple(soft), soft_index)


def _holds(test: Callable[[SceneContext], Any], span: Span, ctx: SceneContext) -> bool:
    return truthy(test(ctx), span)


def require_check(low: LoweringState, req: Require, label: int, soft: int | None) -> RequireCheck:
    """A require as a test on a scene (for rejection)."""
    return RequireCheck(label, functools.partial(_holds, low.compiler.compile(req.condition).fn, req.span), soft)


def _on_p(cond: Callable[[SceneContext], tuple[list, list, list, list]]) -> Callable[[SceneContext], tuple]:
    """A condition's rows with the anchor columns dropped (no anchor: they are zero)."""

    def rows(ctx: SceneContext) -> tuple[list, list, list, list]:
        le_a, le_b, eq_a, eq_b = cond(ctx)
        return [r[:3] for r in le_a], le_b, [r[:3] for r in eq_a], eq_b

    return rows


Lowering = Callable[..., Callable[[SceneContext], tuple[list, list, list, list]] | None]


def _template(low: LoweringState, me: ObjectValue, req: Require, label: int, anchor: str | None,
              lowering: Lowering = lower_condition, lowered: Callable | None = None) -> RowTemplate | None:
    """The require's rows when everything but the target (and the anchor) is constant, else None;
    `lowered` is the condition already lowered with this anchor, if the caller has it."""
    target = me.name
    names = {target} | ({anchor} if anchor else set())
    if not constant_apart_from(low.compiler, req.condition, names):
        return None
    cond = lowered if lowered is not None else lowering(low.compiler, req.condition, target, anchor)
    if cond is None:
        return None
    # Six columns: p's, then the anchor's t.
    poly, bt, dt = rows_polytope(cond(low.fixed_context(me, anchor)), label, 6)
    if not (bt.any() or dt.any()):
        return RowTemplate(poly, None)
    # Rigid: the anchor's columns are minus the target's, so the rows are on p - t.
    if np.allclose(bt, -poly.A, rtol=0, atol=1e-12) and np.allclose(dt, -poly.C, rtol=0, atol=1e-12):
        return RowTemplate(poly, anchor)
    return None


def require_rule(low: LoweringState, me: ObjectValue, req: Require, label: int, soft: int | None, support_known: bool,
                 lowering: Lowering = lower_condition) -> Rule | None:
    """A lowered require as a rule on `me`'s position, or None when it is not linear there."""
    cond = lowering(low.compiler, req.condition, me.name)
    if cond is None:
        return None
    template = None
    if soft is None and support_known:
        template = _template(low, me, req, label, None, lowering, cond)
        if template is None:
            order = sorted((low.index_of[n] for n in mentioned_objects(req.condition) if n != me.name), reverse=True)
            for index in order:
                anchor = low.program.objects[index].name
                if rigid(low.facts, anchor):
                    template = _template(low, me, req, label, anchor, lowering)
                    break
    return Rule("require", label, req.span, (req.condition,), (), template, soft, (_on_p(cond),))


def implied_rule(low: LoweringState, me: ObjectValue, req: Require, label: int, soft: int | None,
                 support_known: bool) -> Rule | None:
    """Rows a hard require that is not linear implies (`distance ... < r`: a box), as a rule that
    narrows `me`'s region; the require is still checked. None for a soft require or none known."""
    if soft is not None:
        return None  # a soft require may be false in a scene: it implies nothing
    return require_rule(low, me, req, label, None, support_known, implied_condition)
