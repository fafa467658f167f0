"""Position specifiers (and the workspace) lowered to rule records with their row templates."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from prsc.constraints import specifier_rows as rows
from prsc.constraints.analysis import CONST, LOCATED_ARGS, common_anchor, motion
from prsc.constraints.build import reads_support, rows_from_values
from prsc.constraints.polytope_ir import CONTAINMENT, POSITION, RELATIVE, RowTemplate, Rule
from prsc.constraints.require_rows import mentioned_objects
from prsc.constraints.state import LoweringState
from prsc.constraints.support import Support
from prsc.constraints.values import ObjectValue
from prsc.errors import PrscError, Span
from prsc.ir import model as ir
from prsc.ir.program import ObjectDecl


def _cause(spec: ir.Specifier) -> str:
    if isinstance(spec, (ir.Direction, ir.AlignedWith)):
        return RELATIVE
    if isinstance(spec, (ir.In, ir.On, ir.ReachableBy, ir.StablyOn, ir.VisibleFrom)):
        return CONTAINMENT
    return POSITION


def _kind_args_options(spec: ir.Specifier) -> tuple[str, tuple[ir.Expr, ...], tuple[tuple[str, Any], ...]]:
    """The rule kind, argument expressions and options of a position specifier."""
    if isinstance(spec, ir.At):
        return "at", (spec.point,), ()
    if isinstance(spec, ir.With):
        return "at", (spec.value,), ()
    if isinstance(spec, ir.Beyond):
        return "beyond", (spec.target, spec.by, spec.origin), ()
    if isinstance(spec, ir.In):
        return "in", (spec.region,), (("completely", spec.completely),)
    if isinstance(spec, ir.On):
        # inside_asset: `completely on` a container asset that declares no interior means
        # inside it (specifiers.interior_of); the relaxed rule of the baseline keeps that.
        return "on", (spec.target,), (("completely", spec.completely), ("inside_asset", spec.completely),
                                      ("inside", spec.inside))
    if isinstance(spec, ir.StablyOn):
        return "stably", (spec.target,), ()
    if isinstance(spec, ir.VisibleFrom):
        return ("not visible" if spec.outside else "visible"), (spec.camera,), ()
    if isinstance(spec, ir.Direction):
        if spec.relation not in rows.DIRECTION_AXES:
            raise PrscError(f"unknown direction {spec.relation!r}", spec.span)
        args = (spec.target,) if spec.by is None else (spec.target, spec.by)
        if spec.up_to is not None:
            args += (spec.up_to,)
        return "direction", args, (("relation", spec.relation),)
    if isinstance(spec, ir.AlignedWith):
        axis = spec.axis.strip("'\"").lower()
        if axis not in ("x", "y", "z"):
            raise PrscError(f"'aligned with' needs the axis x, y or z, not {spec.axis!r}", spec.span)
        return "aligned", (spec.target,), (("axis", axis),)
    if isinstance(spec, ir.ReachableBy):
        return "reachable", (spec.robot,), ()
    raise PrscError(f"unsupported position specifier {type(spec).__name__}", spec.span)


def template(low: LoweringState, rule: Rule, support: Support | None, me: ObjectValue) -> RowTemplate | None:
    """The rule's rows as a template, when its arguments are constant or move with one object.

    Which case applies is read off the argument expressions (analysis.motion); the rows
    are then built once from the constant values, with the anchor at the origin. A
    PrscError from building them (e.g. `beyond V by 0.3 from V`) is the spec's error.
    """
    if reads_support(rule) and support is None:
        return None
    compiler = low.compiler
    motions = [motion(compiler, arg) for arg in rule.args]
    needs = support if support is not None else Support(np.eye(3), np.zeros(3))
    if all(m.kind == CONST for m in motions):
        values = [compiler.compile(arg).value for arg in rule.args]
        return RowTemplate(rows_from_values(rule, values, needs), None)
    anchor = common_anchor(motions, LOCATED_ARGS.get(rule.kind, ()))
    if anchor is None:
        return None
    ctx = low.fixed_context(me, anchor)
    values = [compiler.compile(arg).value if m.kind == CONST else compiler.compile(arg).fn(ctx) for arg, m in zip(rule.args, motions)]
    return RowTemplate(rows_from_values(rule, values, needs), anchor)


def specifier_rules(low: LoweringState, obj: ObjectDecl, spec: ir.Specifier, support: Support | None,
                    me: ObjectValue) -> list[Rule]:
    """The rules of one specifier that sets the position (none for another): its own, and for
    `reachable by R` the two cells about R's base it stays out of (EXCLUSION_KINDS)."""
    if "position" not in spec.sets:
        return []
    kind, args, options = _kind_args_options(spec)
    if kind == "stably":
        args, options = args + stack_below(low, args[0]), _declared_mass(low, obj)
    refs: set[str] = set()
    for arg in args:
        refs |= mentioned_objects(arg)
    label = low.label(obj.name, low.text(spec.span, type(spec).__name__.lower()), spec.span, _cause(spec), tuple(sorted(refs)))
    values = tuple(low.compiler.compile(arg).fn for arg in args)
    rule = _with_template(low, Rule(kind, label, spec.span, args, options, None, None, values), support, me)
    if kind == "on" and rule.option("completely"):
        relaxed_options = (("completely", False), ("inside_asset", True), ("inside", rule.option("inside")))
        relaxed = _with_template(low, Rule(kind, label, spec.span, args, relaxed_options, None, None, values), support, me)
        rule = replace(rule, relaxed=relaxed)
    if kind == "stably":
        # What the rejection baseline draws from: resting on X (the stack's rows are its test).
        relaxed = _with_template(low, Rule("on", label, spec.span, args[:1], (), None, None, values[:1]), support, me)
        rule = replace(rule, relaxed=relaxed)
    if kind == "reachable":
        return [rule, *_reach_hole_rules(low, rule, support, me)]
    return [rule]


def _reach_hole_rules(low: LoweringState, rule: Rule, support: Support | None, me: ObjectValue) -> list[Rule]:
    """The cells a `reachable by R` rule's object stays out of: the hole about R's base and the gap."""
    return [_with_template(low, Rule("unreachable", rule.label_id, rule.span, rule.args, (("part", part),), None,
                                     rule.soft, rule.values), support, me) for part in (0, 1)]


def stack_below(low: LoweringState, target: ir.Expr) -> tuple[ir.Expr, ...]:
    """The supports under a `stably on X` target: what X stands `stably on`, what that stands on, ..."""
    chain: list[ir.Expr] = []
    seen: set[str] = set()
    while isinstance(target, ir.ObjectRef) and target.name not in seen and target.name in low.index_of:
        seen.add(target.name)
        decl = low.program.objects[low.index_of[target.name]]
        _declared_mass(low, decl)
        below = next((s.target for s in decl.specifiers if isinstance(s, ir.StablyOn)), None)
        if not isinstance(below, ir.ObjectRef):
            break
        chain.append(below)
        target = below
    return tuple(chain)


def _declared_mass(low: LoweringState, obj: ObjectDecl) -> tuple[tuple[str, Any], ...]:
    """The object's `mass` as a rule option (none: density times its box volume); in a stack
    it must be a constant, since the rows weigh the objects by it."""
    expr = obj.prop("mass")
    if expr is None:
        return ()
    mass = low.facts.props.get(obj.name, {}).get("mass")
    if isinstance(mass, bool) or not isinstance(mass, (int, float)) or not mass > 0:
        raise PrscError(f"{obj.name} stands in a `stably on` stack, so its mass must be a constant > 0", expr.span)
    return (("mass", float(mass)),)


def workspace_rule(low: LoweringState, obj: ObjectDecl, workspace: ir.Expr, support: Support | None, me: ObjectValue) -> Rule:
    """The workspace as a rule on one object: its box completely inside."""
    span: Span | None = workspace.span
    label = low.label(obj.name, "workspace", span, CONTAINMENT)
    rule = Rule("workspace", label, span, (workspace,), (("completely", True),), None, None, (low.compiler.compile(workspace).fn,))
    return _with_template(low, rule, support, me)


def _with_template(low: LoweringState, rule: Rule, support: Support | None, me: ObjectValue) -> Rule:
    found = template(low, rule, support, me)
    if found is None:
        return rule
    return replace(rule, template=found)
