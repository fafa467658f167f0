"""The typed IR and the front end that builds it: compile_program(path) -> Program."""

from prsc.ir.front_end import compile_program
from prsc.ir.format import format_expr, format_program, format_specifier

__all__ = ["compile_program", "format_expr", "format_program", "format_specifier"]
