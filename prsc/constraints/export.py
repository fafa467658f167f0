"""The constraint IR as JSON-ready data: one entry per rule (what `prsc explain --json` prints)."""

from __future__ import annotations

from typing import Any

from prsc.constraints.polytope_ir import ConstraintProgram, RowLabel, Rule
from prsc.errors import Span
from prsc.geometry.polytope import Polytope
from prsc.ir.format import format_expr


def _source(span: Span | None) -> dict[str, Any] | None:
    if span is None:
        return None
    return {"path": span.path, "line": span.line, "column": span.column, "end_line": span.end_line, "end_column": span.end_column}


def rows_json(poly: Polytope) -> dict[str, list]:
    """Rows `A p <= b`, `C p = d` as lists."""
    return {"A": poly.A.tolist(), "b": poly.b.tolist(), "C": poly.C.tolist(), "d": poly.d.tolist()}


def _entry(label: RowLabel, kind: str, sets: str) -> dict[str, Any]:
    return {
        "object": label.object or None,
        "kind": kind,
        "sets": sets,
        "label": label.text,
        "cause": label.cause,
        "source": _source(label.span),
        "line": None if label.span is None else label.span.line,
        "refs": list(label.refs),
    }


def _position(rule: Rule, label: RowLabel) -> dict[str, Any]:
    entry = _entry(label, rule.kind, "position")
    entry["args"] = [format_expr(a) for a in rule.args]
    entry["options"] = {k: v for k, v in rule.options}
    template = rule.template
    if template is None:
        entry["rows_are"] = "built per scene"
    elif template.anchor is None:
        entry["rows_are"] = "the same in every scene"
    else:
        entry["rows_are"] = f"translated with {template.anchor}"
    entry["anchor"] = None if template is None else template.anchor
    entry["rows"] = None if template is None else rows_json(template.rows)
    entry["soft"] = rule.soft
    return entry


def constraint_ir(cprog: ConstraintProgram) -> dict[str, Any]:
    """Every rule of the program: orientation and position rules per object, then requires checked by rejection."""
    labels = cprog.labels
    rules: list[dict[str, Any]] = []
    objects = []
    for plan in cprog.objects:
        region = plan.region
        objects.append({
            "name": plan.name,
            "class": plan.class_name,
            "source": _source(plan.span),
            "depends_on": list(plan.depends_on),
            "region": "static" if not region.dynamic else ("anchored" if region.anchor else "per scene"),
            "anchor": region.anchor,
            "static_position": None if plan.static_position is None else plan.static_position.tolist(),
        })
        if plan.orientation is not None:
            rule = plan.orientation
            entry = _entry(labels[rule.label_id], rule.kind, "orientation")
            entry["args"] = [format_expr(rule.arg)]
            entry["after_position"] = rule.after_position
            entry["rotation"] = None if rule.static_value is None else rule.static_value.tolist()
            rules.append(entry)
        rules.extend(_position(rule, labels[rule.label_id]) for rule in plan.rules)
        for rule in plan.exclusions:  # rows of a cell the centre stays out of
            entry = _position(rule, labels[rule.label_id])
            entry["sets"] = "position (excluded cell)"
            rules.append(entry)
        for check in plan.checks:
            entry = _entry(labels[check.label_id], "require", "test")
            entry["soft"] = check.soft
            rules.append(entry)
    for check in cprog.scene_checks:
        entry = _entry(labels[check.label_id], "require", "test")
        entry["soft"] = check.soft
        rules.append(entry)
    return {
        "spec": cprog.program.path,
        "order": [plan.name for plan in cprog.objects],
        "objects": objects,
        "rules": rules,
        "soft_requires": [{"index": s.index, "probability": s.probability, "label": labels[s.label_id].text} for s in cprog.soft_requires],
    }
