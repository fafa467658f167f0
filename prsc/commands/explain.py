"""`prsc explain FILE --stage STAGE`: how prsc reads a spec, one compiler stage at a time.

--stage syntax: the syntax tree of FILE alone (imports are not followed), one node per
line with its line:col. --stage ir: the typed IR (names resolved, evaluation order).
--stage constraints (default): the sampler's path (batched, candidate rounds, Gibbs rounds,
sequential + sweeps, sequential, hit-and-run, rejection or baseline) and why, the evaluation
order, then per object its rows
`a . p <= b` / `a . p = b` on its centre p, each with the specifier and source line that
produced it, the region's dimension and length/area/volume, how it is cached, and the
requires checked by rejection, and the cells its centre stays out of (`not visible from C`)
with the measure left. Rows that depend on random values are shown as drawn in
scene --index of --seed. --stage scene: scene --index of --seed as scene JSON, indented
(the same scene `prsc sample` writes on one line).

--json (with --stage constraints): the constraint IR itself as JSON, one entry per rule
(orientation, position and require) with its kind, label, source line, arguments and,
when known at compile time, its rows (with the anchor object they move with).
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

import numpy as np

STAGES = ("syntax", "ir", "constraints", "scene")  # in compiler order
_MEASURE = {0: "point", 1: "length", 2: "area", 3: "volume"}
_UNITS = {0: "", 1: " m", 2: " m^2", 3: " m^3"}


def add_parser(subparsers: Any) -> None:
    """Register `prsc explain`."""
    parser = subparsers.add_parser(
        "explain", help="print a compiler stage of a spec: syntax tree, IR, constraint rows or a scene",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("file", metavar="FILE", help="a .prs spec")
    parser.add_argument("--include", "-I", action="append", default=[], metavar="DIR", help="also search DIR for imports")
    parser.add_argument("--stage", choices=STAGES, default="constraints", help="what to print (default constraints)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the scene whose random values are shown (default 0)")
    parser.add_argument("--index", type=int, default=0, help="index of that scene (default 0)")
    parser.add_argument("--json", action="store_true", help="print the constraint IR as JSON (constraints stage)")


def _linear(a: np.ndarray) -> str:
    """`x - 0.5 y + z` for a coefficient row."""
    terms = []
    for coef, var in zip(a.tolist(), "xyz"):
        if abs(coef) < 1e-12:
            continue
        sign = "-" if coef < 0 else "+"
        mag = abs(coef)
        text = var if abs(mag - 1.0) < 1e-12 else f"{mag:.6g} {var}"
        terms.append((sign, text))
    if not terms:
        return "0"
    first_sign, first = terms[0]
    out = ("-" if first_sign == "-" else "") + first
    for sign, text in terms[1:]:
        out += f" {sign} {text}"
    return out


def _where(span: Any) -> str:
    return "" if span is None else f"{span.path}:{span.line}"


def describe_rows(poly: Any, labels: Any) -> list[str]:
    """One line per row, grouped under the label (specifier) that produced it."""
    lines: list[str] = []
    groups: dict[int, list[str]] = {}
    order: list[int] = []
    for a, b, lab in zip(poly.A, poly.b, poly.labels.tolist()):
        groups.setdefault(lab, []).append(f"{_linear(a)} <= {b:.9g}")
        if lab not in order:
            order.append(lab)
    for c, d, lab in zip(poly.C, poly.d, poly.eq_labels.tolist()):
        groups.setdefault(lab, []).append(f"{_linear(c)} = {d:.9g}")
        if lab not in order:
            order.append(lab)
    for lab in order:
        label = labels[lab] if lab >= 0 else None
        head = "(unlabelled)" if label is None else f"{label.text}  [{label.cause}; {_where(label.span)}]"
        lines.append(f"    {head}")
        lines.extend(f"        {row}" for row in groups[lab])
    return lines


def explain_constraints(sampler: Any, seed: int, index: int) -> str:
    """The constraint-stage report for one compiled sampler."""
    from prsc.geometry.exceptions import GeometryError
    from prsc.geometry.free_space import free_space
    from prsc.sampling.prepared import prepare

    cprog = sampler.constraints
    labels = cprog.labels
    result = sampler.sample(seed, index)
    ctx = result.context
    out = [f"spec: {sampler.spec}", "evaluation order: " + ", ".join(p.name for p in cprog.objects)]
    out.append(sampler.plan.describe())
    out.append(f"rows are on each object's centre p = (x, y, z); random inputs as drawn in scene {index} of seed {seed}")
    if cprog.scene_checks:
        out.append("requires on no object (checked once per scene):")
        out.extend(f"    {labels[c.label_id].text}  [{_where(labels[c.label_id].span)}]" for c in cprog.scene_checks)
    engine_runtimes = sampler.runtimes
    for plan, obj in zip(cprog.objects, result.objects):
        rt = engine_runtimes[plan.index] if plan.index < len(engine_runtimes) else None
        out.append("")
        out.append(f"{plan.name} ({plan.class_name}) declared at {_where(plan.span)}")
        if plan.depends_on:
            out.append(f"  depends on: {', '.join(plan.depends_on)}")
        if plan.orientation is not None:
            lab = labels[plan.orientation.label_id]
            when = "after its position" if plan.orientation.after_position else "before its position"
            out.append(f"  orientation: {lab.text}  [{_where(lab.span)}] ({when})")
        mode = rt.provider.mode if rt is not None else "?"
        cache = {
            "static": "the same every scene (prepared once)",
            "anchored": f"moves with {plan.region.anchor} (prepared once, translated per scene)",
            "general": "rebuilt every scene",
        }.get(mode, mode)
        out.append(f"  region: {cache}")
        half = np.array(obj.dims) * 0.5
        from prsc.constraints.support import Support

        if plan.orientation is not None and plan.orientation.after_position:
            support = Support(None, half, plan.orientation.bound_mode)
        else:
            support = Support(obj.rotation, half, "exact")
        poly = rt.provider.rows(ctx, support) if rt is not None else None
        if poly is not None:
            out.append("  rows:")
            out.extend(describe_rows(poly, labels))
            try:
                region = prepare(poly)
                dim = region.dim
                measure = "a single point" if dim == 0 else f"{_MEASURE[dim]} {region.measure:.6g}{_UNITS[dim]}"
                out.append(f"  feasible region: dimension {dim}, {measure}")
            except GeometryError as error:
                out.append(f"  feasible region: {error}")
        if rt is not None and plan.exclusions:
            out.append("  minus the cells (the centre stays out of each):")
            cells = rt.excluded(ctx, support)
            for cell in cells:
                out.extend(describe_rows(cell, labels))
            try:
                left = free_space(poly, cells)
                out.append(f"  feasible region minus the cells: {_MEASURE[left.region.dim]} {left.measure:.6g}"
                           f"{_UNITS[left.region.dim]} in {len(left.pieces)} convex pieces")
            except GeometryError as error:
                out.append(f"  feasible region minus the cells: {error}")
        for check in plan.checks:
            lab = labels[check.label_id]
            out.append(f"  checked by rejection: {lab.text}  [{_where(lab.span)}]")
        out.append(f"  sampled position: {np.round(obj.position, 6).tolist()}")
    if sampler.program.task:
        from prsc.task.describe import describe_statements

        out.append("")
        out.append("task, evaluated on the simulated state at every control step (docs/tasks.md):")
        out.extend(f"  {line}" for line in describe_statements(sampler.program.task))
    return "\n".join(out) + "\n"


def run(args: argparse.Namespace) -> int:
    """Print the requested stage."""
    if args.json and args.stage != "constraints":
        from prsc.errors import PrscError

        raise PrscError(f"--json prints the constraints stage (the scene stage is JSON already), not --stage {args.stage}")
    if args.stage == "syntax":
        from prsc.syntax import parse_file
        from prsc.syntax.ast_text import format_ast

        sys.stdout.write(format_ast(parse_file(args.file)))
        return 0
    if args.stage == "ir":
        from prsc.ir import compile_program, format_program

        sys.stdout.write(format_program(compile_program(args.file, args.include)))
        sys.stdout.write("\n")
        return 0
    if args.json:
        from prsc.constraints import lower_program
        from prsc.constraints.export import constraint_ir
        from prsc.ir import compile_program

        cprog = lower_program(compile_program(args.file, args.include))
        sys.stdout.write(json.dumps(constraint_ir(cprog), indent=1, allow_nan=False) + "\n")
        return 0
    from prsc.sampling import compile_sampler

    sampler = compile_sampler(args.file, args.include)
    if args.stage == "scene":
        sys.stdout.write(json.dumps(sampler.scene(args.seed, args.index), indent=2, allow_nan=False) + "\n")
        return 0
    sys.stdout.write(explain_constraints(sampler, args.seed, args.index))
    return 0
