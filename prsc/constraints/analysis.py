"""Analyses of the constraint IR: plain functions over expressions and rule records.

Nothing here runs a rule to learn about it: what an argument depends on is read off its
IR expression (constant folding, or a located value that moves rigidly with one earlier
object), and what a region needs is read off its rules' templates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from prsc.constraints.evaluate import ExprCompiler, StaticFacts
from prsc.constraints.polytope_ir import RegionRules, Rule
from prsc.constraints.values import static_dims
from prsc.geometry.polytope import Polytope, intersect
from prsc.ir import model as ir

CONST = "const"
MOVES = "moves"
OTHER = "other"

# Per rule kind, the arguments that are locations (objects, points): the rows move
# rigidly with an object when every location moves with it and the rest is constant.
LOCATED_ARGS = {
    "at": (0,),
    "beyond": (0, 2),
    "on": (0,),
    "direction": (0,),
    "aligned": (0,),
    "reachable": (0,),
    "unreachable": (0,),
    "stably": tuple(range(64)),  # the support and every support under it
    "visible": (0,),
    "not visible": (0,),
    "in": (),
    "workspace": (),
    "require": (),
}

# Kinds whose rows fix p to one point given their arguments (`at V`).
POINT_KINDS = frozenset({"at", "beyond"})


@dataclass(frozen=True)
class Motion:
    """How an expression's value changes between scenes: constant, moves with `anchor`, or otherwise."""

    kind: str
    anchor: str | None = None


def rigid(facts: StaticFacts, name: str) -> bool:
    """Whether an object's rotation and size are fixed and only its position is random."""
    return name in facts.rotations and name not in facts.positions and static_dims(facts.props.get(name, {})) is not None


def motion(compiler: ExprCompiler, expr: ir.Expr) -> Motion:
    """Whether `expr` is constant, a location moving rigidly with one object, or neither."""
    if compiler.compile(expr).const:
        return Motion(CONST)
    facts = compiler.facts
    if isinstance(expr, ir.ObjectRef):
        return Motion(MOVES, expr.name) if rigid(facts, expr.name) else Motion(OTHER)
    if isinstance(expr, ir.FacePoint) or (isinstance(expr, ir.PropertyRef) and expr.prop == "position"):
        inner = expr.target
        if isinstance(inner, ir.ObjectRef) and rigid(facts, inner.name):
            return Motion(MOVES, inner.name)
        return Motion(OTHER)
    if isinstance(expr, ir.BinOp) and expr.op in "+-":
        left, right = motion(compiler, expr.left), motion(compiler, expr.right)
        if left.kind == MOVES and right.kind == CONST and expr.right.type == ir.Type.VECTOR:
            return left
        if expr.op == "+" and right.kind == MOVES and left.kind == CONST and expr.left.type == ir.Type.VECTOR:
            return right
        return Motion(OTHER)
    if isinstance(expr, ir.RelativeTo):
        value, frame = motion(compiler, expr.value), motion(compiler, expr.frame)
        if value.kind == CONST and frame.kind == MOVES:
            return frame
    return Motion(OTHER)


def common_anchor(motions: list[Motion], located: tuple[int, ...]) -> str | None:
    """The object every located argument moves with (the others constant), else None."""
    if any(m.kind == OTHER for m in motions):
        return None
    anchors = {motions[i].anchor for i in located if i < len(motions)}
    others_const = all(m.kind == CONST for i, m in enumerate(motions) if i not in located)
    if len(anchors) == 1 and None not in anchors and others_const:
        return anchors.pop()
    return None


def pinned_point(poly: Polytope) -> np.ndarray | None:
    """The single point the equality rows fix (rank 3), else None."""
    if poly.C.shape[0] < 3:
        return None
    _, s, _ = np.linalg.svd(poly.C)
    if s[2] <= 1e-9 * max(1.0, s[0]):
        return None
    point, *_ = np.linalg.lstsq(poly.C, poly.d, rcond=None)
    return point


def region_rules(rules: list[Rule] | tuple[Rule, ...]) -> RegionRules:
    """Stack the static rules; anchor the others when their templates share one anchor."""
    static_list = [r.rows for r in rules if r.static and r.rows is not None]
    static_rows = intersect(*static_list) if static_list else None
    dynamic = [r for r in rules if not r.static]
    anchor, anchored_rows = None, None
    anchors = {r.template.anchor if r.template is not None else None for r in dynamic}
    if dynamic and len(anchors) == 1 and None not in anchors and all(r.soft is None for r in dynamic):
        anchor = anchors.pop()
        anchored_rows = intersect(*(r.template.rows for r in dynamic))  # type: ignore[union-attr]
    point_rule = next((i for i, r in enumerate(rules) if not r.static and r.kind in POINT_KINDS and r.soft is None), None)
    return RegionRules(tuple(rules), static_rows, anchor, anchored_rows, point_rule)
