"""Rows of a position rule in one scene: the rule's row builder, looked up by its kind."""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from prsc.constraints import specifier_rows as rows
from prsc.constraints.context import SceneContext
from prsc.constraints.polytope_ir import Rule
from prsc.constraints.reach_rows import rows_reachable, rows_unreachable
from prsc.constraints.stacks import rows_stably
from prsc.constraints.support import Support
from prsc.constraints.visibility import rows_visible
from prsc.geometry.polytope import Polytope
from prsc.ir.builtins import default_mass

Builder = Callable[[Rule, list[Any], Support], Polytope]


def rows_polytope(values: tuple[list, list, list, list], label: int, columns: int = 3) -> tuple[Polytope, np.ndarray, np.ndarray]:
    """(rows on p, the further columns of the inequalities, of the equalities) from rows
    (le_a, le_b, eq_a, eq_b) of `columns` columns, p's the first three."""
    le_a, le_b, eq_a, eq_b = values
    a = np.array(le_a, dtype=float).reshape(-1, columns)
    c = np.array(eq_a, dtype=float).reshape(-1, columns)
    poly = Polytope(a[:, :3], np.array(le_b, dtype=float), c[:, :3], np.array(eq_b, dtype=float),
                    np.full(len(a), label), np.full(len(c), label))
    return poly, a[:, 3:], c[:, 3:]


def _require_rows(rule: Rule, values: list[Any], support: Support) -> Polytope:
    return rows_polytope(values[0], rule.label_id)[0]


BUILDERS: dict[str, Builder] = {
    "at": lambda r, v, s: rows.rows_at(v[0], r.label_id, r.span),
    "beyond": lambda r, v, s: rows.rows_beyond(v[0], v[1], v[2], r.label_id, r.span),
    "in": lambda r, v, s: rows.rows_in(v[0], r.option("completely"), s, r.label_id, r.span),
    "on": lambda r, v, s: rows.rows_on(v[0], r.option("completely"), s, r.label_id, r.span, bool(r.option("inside_asset")),
                                       bool(r.option("inside"))),
    "stably": lambda r, v, s: rows_stably(v, r.option("mass") or default_mass(*(2.0 * s.half)), s, r.label_id, r.span),
    "visible": lambda r, v, s: rows_visible(v[0], s, r.label_id, r.span),
    # The excluded cell (ObjectPlan.exclusions): the centres where the box is wholly in view.
    "not visible": lambda r, v, s: rows_visible(v[0], s, r.label_id, r.span, "not visible from"),
    "direction": lambda r, v, s: rows.rows_direction(r.option("relation"), v[0], v[1] if len(v) > 1 else None, s, r.label_id, r.span,
                                                     v[2] if len(v) > 2 else None),
    "aligned": lambda r, v, s: rows.rows_aligned(v[0], r.option("axis"), r.label_id, r.span),
    "workspace": lambda r, v, s: rows.rows_in(v[0], True, s, r.label_id, r.span),
    "require": _require_rows,
    "reachable": lambda r, v, s: rows_reachable(v[0], r.label_id, r.span),
    "unreachable": lambda r, v, s: rows_unreachable(v[0], r.option("part"), r.label_id, r.span),
}

# Kinds whose rows never read the object's own box (its support function).
SIZE_FREE = frozenset({"at", "beyond", "aligned", "reachable", "unreachable"})


def reads_support(rule: Rule) -> bool:
    """Whether the rule's rows depend on the object's size or rotation."""
    if rule.kind == "in":
        return bool(rule.option("completely"))
    return rule.kind not in SIZE_FREE


def rows_from_values(rule: Rule, values: list[Any], support: Support) -> Polytope:
    """The rule's rows for concrete argument values."""
    return BUILDERS[rule.kind](rule, values, support)


def rule_rows(rule: Rule, ctx: SceneContext, support: Support) -> Polytope:
    """The rule's rows in one scene."""
    if rule.static:
        return rule.template.rows  # type: ignore[union-attr]
    return BUILDERS[rule.kind](rule, [f(ctx) for f in rule.values], support)


def excluded_cells(rules: tuple[Rule, ...], ctx: SceneContext, support: Support) -> list[Polytope]:
    """The convex cells an object's centre must stay out of in one scene (ObjectPlan.exclusions),
    each once: `reachable by` an arm that turns all the way round has no gap, and its gap cell
    repeats its hole, which the free-space decomposition would otherwise subtract twice."""
    cells: list[Polytope] = []
    for rule in rules:
        rows = rule_rows(rule, ctx, support)
        if not any(rows.same_rows(cell) for cell in cells):
            cells.append(rows)
    return cells
