"""The rejection baseline's draw regions: equalities and `on` surfaces, in the workspace's box.

As the original sampled: each object is drawn uniformly from the workspace's bounding
box cut by its equalities (`at`, `beyond`, `aligned with`) and, for `on X` (and `stably on
X`), X's surface without erosion; every other rule is a test on the draw (rejection.py).
"""

from __future__ import annotations

from prsc.constraints.analysis import region_rules
from prsc.constraints.polytope_ir import ConstraintProgram, ObjectPlan, RegionRules, RowTemplate, Rule

DRAWN_KINDS = frozenset({"at", "beyond", "aligned"})


def baseline_region(cprog: ConstraintProgram, plan: ObjectPlan) -> RegionRules:
    """The region the baseline draws one object's position from."""
    rules: list[Rule] = [r for r in plan.rules if r.kind in DRAWN_KINDS]
    rules += [r.relaxed or r for r in plan.rules if r.kind in ("on", "stably")]
    box = cprog.workspace_box
    workspace = next((r for r in plan.rules if r.kind == "workspace"), None)
    if box is not None and workspace is not None:
        rows = box.with_label(workspace.label_id)
        rules.append(Rule("box", workspace.label_id, workspace.span, (), (), RowTemplate(rows, None)))
    return region_rules(rules)
