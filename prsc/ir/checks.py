"""Checks on a Program's constant values that `prsc check` can make before any sampling:
sizes a simulator can represent, and mesh files that exist."""

from __future__ import annotations

from typing import Sequence

from prsc.errors import PrscError
from prsc.ir import model as ir
from prsc.limits import mass_problem, size_problem
from prsc.mesh_paths import mesh_folders, resolve_mesh

SIZES = ("width", "length", "height")


def constant_number(expr: ir.Expr) -> float | None:
    """The value of a constant arithmetic expression, or None."""
    if isinstance(expr, ir.Const) and expr.type == ir.Type.SCALAR:
        return float(expr.value)
    if isinstance(expr, ir.UnaryOp) and expr.op in "+-":
        inner = constant_number(expr.operand)
        return None if inner is None else (-inner if expr.op == "-" else inner)
    if isinstance(expr, ir.BinOp):
        a, b = constant_number(expr.left), constant_number(expr.right)
        if a is None or b is None or (expr.op == "/" and b == 0):
            return None
        try:
            return {"+": a + b, "-": a - b, "*": a * b, "/": a / b if b else 0.0}[expr.op]
        except (OverflowError, KeyError):
            return None
    return None


def _constant_string(expr: ir.Expr | None) -> str | None:
    if isinstance(expr, ir.Const) and expr.type == ir.Type.STRING:
        return str(expr.value)
    return None


def check_values(program: ir.Program, include_dirs: Sequence[str] = ()) -> None:
    """Raise a PrscError at the value's place for a constant size or mass a simulator cannot
    hold, or a constant mesh file that cannot be found."""
    for obj in program.objects:
        for prop in SIZES:
            expr = obj.prop(prop)
            value = None if expr is None else constant_number(expr)
            problem = None if value is None else size_problem(value)
            if problem:
                raise PrscError(f"{prop} of {obj.name} {problem}", expr.span)  # type: ignore[union-attr]
        mass = obj.prop("mass")
        value = None if mass is None else constant_number(mass)
        problem = None if value is None else mass_problem(value)
        if problem:
            raise PrscError(f"mass of {obj.name} {problem}", mass.span)  # type: ignore[union-attr]
        mesh = obj.prop("mesh")
        raw = _constant_string(mesh)
        if raw is not None and (_constant_string(obj.prop("shape")) or "").strip().lower() == "mesh":
            try:
                # Existence only: whether a path outside the spec's folders may be read is
                # the compiling command's decision (--meshes-anywhere).
                resolve_mesh(raw, mesh_folders(program.path, include_dirs), anywhere=True)
            except PrscError as error:
                raise PrscError(f"{obj.name}: {error.message}", mesh.span) from None  # type: ignore[union-attr]
