"""Checks on a Program's constant values that `prsc check` can make before any sampling:
sizes and masses a simulator can represent (mesh files are found by prsc/ir/mesh_sizes.py)."""

from __future__ import annotations

from prsc.errors import PrscError
from prsc.ir import model as ir
from prsc.ir.program import Program
from prsc.limits import mass_problem, size_problem

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


def check_values(program: Program) -> None:
    """Raise a PrscError at the value's place for a constant size or mass a simulator cannot hold."""
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
