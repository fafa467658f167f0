"""Readable text for IR expressions, specifiers and whole programs (`prsc check`, `prsc explain`)."""

from __future__ import annotations

import math

from prsc.ir import model as ir
from prsc.ir.program import ObjectDecl, Program, SelfRef
from prsc.ir.builtins import DIRECTION_PHRASES, joint_name

_PRECEDENCE = {"or": 1, "and": 2, "not": 3, "compare": 4, "relative": 5, "+": 6, "-": 6, "*": 7, "/": 7,
               "unary": 8}
_DISTRIBUTION_NAMES = {"range": "Range", "normal": "Normal", "truncnormal": "TruncatedNormal",
                       "uniform": "Uniform", "discrete": "Discrete"}
_REGION_NAMES = {"cuboid": "Cuboid", "rectangle": "Rectangle", "halfspace": "HalfSpace",
                 "polygon": "ConvexPolygon3D", "polyhedron": "ConvexPolyhedron",
                 "intersection": "Intersection", "all": "All", "empty": "Empty"}


def format_number(value: float) -> str:
    """A number as short as it reads exactly: 0, 1.8, -0.4, 0.0174533 for a degree."""
    if isinstance(value, bool):
        return str(value)
    if math.isfinite(value) and value == int(value) and abs(value) < 1e15:
        return str(int(value))
    text = repr(float(value))
    short = f"{value:.6g}"
    return short if len(short) < len(text) and abs(float(short) - value) < 1e-9 * max(1.0, abs(value)) else text


def _prec(expr: ir.Expr) -> int:
    if isinstance(expr, ir.BinOp):
        return _PRECEDENCE[expr.op]
    if isinstance(expr, ir.BoolOp):
        return _PRECEDENCE[expr.op]
    if isinstance(expr, ir.Compare):
        return _PRECEDENCE["compare"]
    if isinstance(expr, ir.RelativeTo):
        return _PRECEDENCE["relative"]
    if isinstance(expr, ir.UnaryOp):
        return _PRECEDENCE["not" if expr.op == "not" else "unary"]
    if isinstance(expr, ir.FacePoint):
        return 8
    return 10


def _wrap(expr: ir.Expr, at_least: int) -> str:
    text = format_expr(expr)
    return f"({text})" if _prec(expr) < at_least else text


def format_expr(expr: ir.Expr) -> str:
    """Source-like text of an IR expression."""
    if isinstance(expr, ir.Const):
        if expr.type == ir.Type.STRING:
            return '"' + str(expr.value).replace("\\", "\\\\").replace('"', '\\"') + '"'
        if isinstance(expr.value, (tuple, list)):  # a constant vector (a file asset's rootOffset)
            return "Vector3D(" + ", ".join(format_number(float(v)) for v in expr.value) + ")"
        return format_number(expr.value) if not isinstance(expr.value, bool) else str(expr.value)
    if isinstance(expr, ir.VectorExpr):
        return f"Vector3D({format_expr(expr.x)}, {format_expr(expr.y)}, {format_expr(expr.z)})"
    if isinstance(expr, ir.ListExpr):
        return "[" + ", ".join(format_expr(i) for i in expr.items) + "]"
    if isinstance(expr, (ir.ObjectRef, ir.VarRef)):
        return expr.name
    if isinstance(expr, SelfRef):
        return f"self.{expr.prop}"
    if isinstance(expr, ir.PropertyRef):
        return f"{_wrap(expr.target, 10)}.{expr.prop}"
    if isinstance(expr, ir.FacePoint):
        return f"{' '.join(expr.words)} {_wrap(expr.target, 9)}"
    if isinstance(expr, ir.RelativeTo):
        return f"{_wrap(expr.value, 6)} relative to {_wrap(expr.frame, 6)}"
    if isinstance(expr, ir.BinOp):
        p = _PRECEDENCE[expr.op]
        return f"{_wrap(expr.left, p)} {expr.op} {_wrap(expr.right, p + 1)}"
    if isinstance(expr, ir.UnaryOp):
        if expr.op == "not":
            return f"not {_wrap(expr.operand, 3)}"
        return f"{expr.op}{_wrap(expr.operand, 8)}"
    if isinstance(expr, ir.Compare):
        return f"{_wrap(expr.left, 5)} {expr.op} {_wrap(expr.right, 5)}"
    if isinstance(expr, ir.BoolOp):
        p = _PRECEDENCE[expr.op]
        return f" {expr.op} ".join(_wrap(o, p + 1) for o in expr.operands)
    if isinstance(expr, ir.Distance):
        return f"(distance from {_wrap(expr.source, 9)} to {_wrap(expr.target, 9)})"
    if isinstance(expr, ir.Call):
        return f"{expr.func}(" + ", ".join(format_expr(a) for a in expr.args) + ")"
    if isinstance(expr, ir.Distribution):
        if expr.kind == "range":
            return f"({format_expr(expr.args[0])}, {format_expr(expr.args[1])})"
        if expr.kind == "discrete":
            items = ", ".join(f"{format_expr(v)}: {format_expr(w)}" for v, w in zip(expr.args, expr.weights))
            return f"Discrete({{{items}}})"
        return f"{_DISTRIBUTION_NAMES[expr.kind]}(" + ", ".join(format_expr(a) for a in expr.args) + ")"
    if isinstance(expr, ir.SurfaceRef):
        return f"{_wrap(expr.target, 10)}.{expr.name}[{format_expr(expr.index)}]"
    if isinstance(expr, ir.LinkRef):
        return f"{_wrap(expr.target, 10)}.links[{expr.name!r}]"
    if isinstance(expr, ir.RegionExpr):
        args = ", ".join(f"{k}={format_expr(v)}" for k, v in expr.args)
        return f"{_REGION_NAMES.get(expr.kind, expr.kind)}({args})"
    return f"<{type(expr).__name__}>"  # pragma: no cover


def _arg(expr: ir.Expr) -> str:
    """A specifier argument: a face point keeps its brackets (`left of (top table)`)."""
    return f"({format_expr(expr)})" if isinstance(expr, ir.FacePoint) else format_expr(expr)


def format_specifier(spec: ir.Specifier) -> str:
    """Source-like text of a specifier."""
    if isinstance(spec, ir.With):
        joint = joint_name(spec.prop)
        if joint is not None:
            return f"with joint {joint!r} {_arg(spec.value)}"
        return f"with {spec.prop} {_arg(spec.value)}"
    if isinstance(spec, ir.At):
        return f"at {_arg(spec.point)}"
    if isinstance(spec, ir.In):
        return f"{'completely ' if spec.completely else ''}in {_arg(spec.region)}"
    if isinstance(spec, ir.On):
        return f"{'completely ' if spec.completely else ''}{'in' if spec.inside else 'on'} {_arg(spec.target)}"
    if isinstance(spec, ir.StablyOn):
        return f"stably on {_arg(spec.target)}"
    if isinstance(spec, ir.VisibleFrom):
        return f"{'not ' if spec.outside else ''}visible from {_arg(spec.camera)}"
    if isinstance(spec, ir.Direction):
        word = DIRECTION_PHRASES.get(spec.relation, spec.relation)
        by = f" by {_arg(spec.by)}" if spec.by is not None else ""
        if spec.up_to is not None:
            by = f" by ({_arg(spec.by)}, {_arg(spec.up_to)})"
        return f"{word} {_arg(spec.target)}{by}"
    if isinstance(spec, ir.Beyond):
        return f"beyond {_arg(spec.target)} by {_arg(spec.by)} from {_arg(spec.origin)}"
    if isinstance(spec, ir.AlignedWith):
        return f"aligned with {_arg(spec.target)} on {spec.axis}"
    if isinstance(spec, ir.Facing):
        return f"facing {_arg(spec.direction)}"
    if isinstance(spec, ir.FacingToward):
        return f"facing toward {_arg(spec.target)}"
    if isinstance(spec, ir.ReachableBy):
        return f"reachable by {_arg(spec.robot)}"
    return type(spec).__name__  # pragma: no cover


def format_object(obj: ObjectDecl, verbose: bool = True) -> str:
    """An object: name, class, properties and its specifiers in evaluation order."""
    label = f"{obj.name}: {obj.class_name}" + (" (anonymous)" if obj.anonymous else "")
    lines = [f"{label}  [line {obj.span.line}]"]
    if verbose:
        props = ", ".join(f"{k}={format_expr(v)}" for k, v in obj.properties)
        lines.append(f"    properties: {props}")
        if obj.depends_on:
            lines.append(f"    depends on: {', '.join(obj.depends_on)}")
    for i, spec in enumerate(obj.specifiers, start=1):
        reads = f"; reads {', '.join(spec.reads)}" if spec.reads else ""
        free = "; orientation-free bound" if spec.orientation_free else ""
        lines.append(f"    {i}. {format_specifier(spec)}    (sets {', '.join(spec.sets)}{reads}{free})")
    return "\n".join(lines)


def format_program(program: Program) -> str:
    """A readable dump of a whole Program."""
    out = [f"program {program.path}"]
    if len(program.source_files) > 1:
        out.append(f"  imports: {', '.join(program.source_files[1:])}")
    out.append(f"  workspace: {format_expr(program.workspace) if program.workspace is not None else 'All()'}")
    user_classes = [c for c in program.classes if c.parent is not None]
    if user_classes:
        out.append(f"classes ({len(user_classes)}):")
        for c in user_classes:
            defaults = "; ".join(format_specifier(s) for s in c.specifiers)
            out.append(f"  {c.name}({c.parent})" + (f"  default: {defaults}" if defaults else ""))
    if program.variables:
        out.append(f"variables ({len(program.variables)}):")
        for v in program.variables:
            out.append(f"  {v.name} = {format_expr(v.value)}")
    if program.params:
        out.append(f"params ({len(program.params)}):")
        for p in program.params:
            out.append(f"  {p.name} = {format_expr(p.value)}")
    out.append(f"objects ({len(program.objects)}), in evaluation order:")
    for obj in program.objects:
        out.append("  " + format_object(obj).replace("\n", "\n  "))
    if program.requires:
        out.append(f"requires ({len(program.requires)}):")
        for r in program.requires:
            p = "" if r.probability == 1.0 else f"[{format_number(r.probability)}]"
            out.append(f"  require{p} {format_expr(r.condition)}  [line {r.span.line}]")
    return "\n".join(out) + "\n"
