"""Bounded repetition: the values of `for i in range(...)` and the names a loop body binds.

A loop is unrolled by the front end (docs/language.md, "Repetition"): its bounds must be
constant whole numbers, known before any scene is drawn, and a spec unrolls at most
MAX_LOOP_ITERATIONS iterations in all.
"""

from __future__ import annotations

import itertools
from typing import Callable, Sequence

from prsc.errors import PrscError, Span
from prsc.ir import model as ir
from prsc.ir.builtins import ROOT_CLASS
from prsc.ir.checks import constant_number
from prsc.ir.expressions import DrawIds, ExprResolver
from prsc.ir.scope import ConstantInfo, LoopNames, ObjectInfo, Scope, VariableInfo, describe
from prsc.syntax import nodes

# Every iteration of every loop, nested ones counted per outer iteration. A scene of more
# objects than this samples and simulates far too slowly to be what the spec meant.
MAX_LOOP_ITERATIONS = 1000


def _whole_number(expr: ir.Expr, value_of: Callable[[ir.Expr], float | None]) -> int:
    """A range() bound as an int, or an error at the argument."""
    if expr.type not in (ir.Type.SCALAR, ir.Type.ANY):
        raise PrscError(f"range() needs whole numbers, not {'an' if expr.type.value[0] in 'aeiou' else 'a'} "
                        f"{expr.type.value}", expr.span)
    value = value_of(expr)
    if value is None:
        raise PrscError("range() needs constant whole numbers: a loop is unrolled before any scene is drawn, "
                        "so its bounds cannot be random or read from objects", expr.span)
    if value != int(value):
        raise PrscError(f"range() needs whole numbers, not {value:g}", expr.span)
    return int(value)


def loop_values(loop: nodes.ForLoop, args: tuple[ir.Expr, ...],
                value_of: Callable[[ir.Expr], float | None] = constant_number) -> range:
    """The values the loop variable takes: Python's range(stop), range(start, stop[, step])."""
    if loop.function != "range":
        raise PrscError(f"a loop runs over range(n) or range(start, stop), not {loop.function}(...)",
                        loop.function_span)
    if not 1 <= len(args) <= 3:
        raise PrscError(f"range() takes 1 to 3 whole numbers (stop; start, stop; start, stop, step), "
                        f"got {len(args)}", loop.function_span)
    numbers = [_whole_number(a, value_of) for a in args]
    if len(numbers) == 3 and numbers[2] == 0:
        raise PrscError("range() step must not be zero", args[2].span)
    return range(*numbers)


def literal_count(loop: nodes.ForLoop) -> int | None:
    """How many times a loop runs when its bounds are written as numbers, else None."""

    def literal(expr: nodes.Expr) -> float | None:
        if isinstance(expr, nodes.Number):
            return expr.value
        if isinstance(expr, nodes.UnaryOp) and expr.op == "-":
            inner = literal(expr.operand)
            return None if inner is None else -inner
        return None

    values = [literal(a) for a in loop.args]
    if loop.function != "range" or not 1 <= len(values) <= 3 or any(v is None or v != int(v) for v in values):
        return None
    if len(values) == 3 and values[2] == 0:
        return None
    return len(range(*(int(v) for v in values)))  # type: ignore[arg-type]


def iteration_name(name: str, iterations: tuple[int, ...]) -> str:
    """The object a name in a loop body gives in one iteration: `cup` -> `cup_3`, nested `cup_1_0`."""
    return name + "".join(f"_{k}" for k in iterations)


def bound_names(statements: Sequence[nodes.Statement], counts: tuple[int | None, ...], out: dict[str, Span]) -> None:
    """Add the names statements bind; in loops of literal bounds (counts) also `name_k`."""
    for s in statements:
        if isinstance(s, nodes.ForLoop):
            out.setdefault(s.var, s.var_span)
            bound_names(s.body, counts + (literal_count(s),), out)
            continue
        name, span = binding_of(s)
        if name is None or span is None:
            continue
        out.setdefault(name, span)
        if counts and None not in counts and _product(counts) <= MAX_LOOP_ITERATIONS:
            for ks in itertools.product(*(range(c) for c in counts if c is not None)):
                out.setdefault(iteration_name(name, ks), span)


def _product(counts: tuple[int | None, ...]) -> int:
    total = 1
    for c in counts:
        total *= c or 0
    return total


def binding_of(s: nodes.Statement) -> tuple[str | None, Span | None]:
    """The name a statement binds and where, or (None, None)."""
    if isinstance(s, nodes.Assign):
        return s.target, s.target_span
    if isinstance(s, nodes.ObjectStmt) and s.name:
        return s.name, s.name_span
    if isinstance(s, nodes.ClassDef):
        return s.name, s.name_span
    return None, None


class LoopStatements:
    """The Compiler's handling of `for` statements (a mixin: it reads the Compiler's state)."""

    scope: Scope
    draws: DrawIds
    exports: dict[str, dict[str, object]]
    current: list[str]
    iterations: tuple[int, ...]  # the iteration number of each enclosing loop
    iterations_used: int  # in all loops so far, against MAX_LOOP_ITERATIONS

    def _statement(self, s: nodes.Statement) -> None:  # pragma: no cover - the Compiler's
        raise NotImplementedError

    def _loop(self, s: nodes.ForLoop) -> None:
        """Unroll `for var in range(...)`: the body once per value, var a constant in it."""
        args = tuple(ExprResolver(self.scope, self.draws).resolve(a) for a in s.args)
        values = loop_values(s, args, self._constant_value)
        end = args[-1].span if args else s.function_span
        range_span = Span(s.span.path, s.function_span.line, s.function_span.column, end.end_line, end.end_column + 1)
        total = self.iterations_used + len(values)
        if total > MAX_LOOP_ITERATIONS:
            more = f", which brings the spec's loops to {total} iterations" if total > len(values) else ""
            raise PrscError(f"this loop runs {len(values)} times{more}; a spec unrolls at most "
                            f"{MAX_LOOP_ITERATIONS} loop iterations in all", range_span)
        self.iterations_used += len(values)
        if s.var in (ROOT_CLASS, "self", "workspace"):
            raise PrscError(f"'{s.var}' cannot be a loop variable", s.var_span)
        existing = self.scope.names.get(s.var)
        if existing is not None and not isinstance(existing, (VariableInfo, ConstantInfo, LoopNames)):
            raise PrscError(f"'{s.var}' is already {describe(existing)}: a loop variable needs a name of its own",
                            s.var_span)
        for statement in s.body:
            if isinstance(statement, (nodes.ImportFrom, nodes.ImportModule, nodes.ParamStmt)):
                what = "a param" if isinstance(statement, nodes.ParamStmt) else "an import"
                raise PrscError(f"{what} cannot be in a loop body: it is made once per spec, so write it "
                                "before the loop", statement.span)
        bound: dict[str, Span] = {}
        bound_names(s.body, (), bound)  # nested loops' names too: none outlives this loop
        if s.var in bound:
            raise PrscError(f"the loop variable '{s.var}' cannot be bound in the loop body", bound[s.var])
        bound[s.var] = s.var_span
        exports = self.exports[self.current[-1]]
        saved = {name: (self.scope.names.get(name), exports.get(name)) for name in bound}
        named: dict[str, list[str]] = {name: [] for name in bound}
        for k, value in enumerate(values):
            self.scope.names[s.var] = ConstantInfo(float(value), s.var_span)
            self.iterations += (k,)
            try:
                for statement in s.body:
                    self._statement(statement)
            finally:
                self.iterations = self.iterations[:-1]
            for name in bound:
                binding = self.scope.names.get(name)
                if isinstance(binding, ObjectInfo):
                    named[name].append(binding.name)
                elif isinstance(binding, LoopNames):  # a nested loop's objects
                    named[name].extend(binding.objects)
                self._restore(name, *saved[name])
        for name in bound:  # after the loop a name of its body means nothing by itself
            if saved[name][0] is None:
                self.scope.names[name] = LoopNames(name, tuple(named[name]), s.span)

    def _restore(self, name: str, binding, exported) -> None:
        """Put a name back as it was before a loop iteration bound it."""
        exports = self.exports[self.current[-1]]
        for table, value in ((self.scope.names, binding), (exports, exported)):
            if value is None:
                table.pop(name, None)
            else:
                table[name] = value

    def _constant_value(self, expr: ir.Expr) -> float | None:
        """A constant number, following variables bound to constants (for loop bounds)."""
        for _ in range(100):
            if not isinstance(expr, ir.VarRef):
                break
            info = self.scope.variables.get(expr.name)
            if info is None:
                return None
            expr = info.value
        return constant_number(expr)
