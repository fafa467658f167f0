"""A compiled task in words: each statement as the spec writes it, for `prsc check` and `prsc explain`."""

from __future__ import annotations

from prsc.task.terms import DIRECTIONS, TaskStatements, Term

_RELATION_WORDS = {"in": "in", "on": "on", "touches": "touches", "holds": "holds", "visible": "visible from",
                   **{d: f"{d} of" if d in ("left", "right", "ahead") else d for d in DIRECTIONS}}


def format_term(term: Term) -> str:
    """A term as spec text."""
    op, args = term.op, term.args
    if op == "const":
        return f"{term.value:g}"
    if op == "object":
        return str(term.name)
    if op == "link":
        return f'{format_term(args[0])}.links["{term.name}"]'
    if op == "true":
        return "True"
    if op == "vector":
        return "Vector3D(" + ", ".join(format_term(a) for a in args) + ")"
    if op == "attr":
        return f"{format_term(args[0])}.{term.name}"
    if op == "neg":
        return f"-{format_term(args[0])}"
    if op in ("arith", "compare"):
        return f"({format_term(args[0])} {term.name} {format_term(args[1])})"
    if op == "distance":
        return f"distance from {format_term(args[0])} to {format_term(args[1])}"
    if op in ("and", "or"):
        return "(" + f" {op} ".join(format_term(a) for a in args) + ")"
    if op == "not":
        return f"not {format_term(args[0])}"
    if op == "at_rest":
        return f"{format_term(args[0])} at rest"
    if op == "upright":
        return f"{format_term(args[0])} upright"
    text = f"{format_term(args[0])} {'completely ' if term.completely else ''}{_RELATION_WORDS[op]} {format_term(args[1])}"
    return text + (f" by {format_term(args[2])}" if len(args) > 2 else "")


def describe_statements(task: TaskStatements) -> list[str]:
    """One line per task statement."""
    lines = [f"goal {format_term(g.expr)} for {g.hold:g} seconds  [line {g.line}]" for g in task.goals]
    lines += [f'fail "{f.label}" when {format_term(f.expr)}  [line {f.line}]' for f in task.failures]
    if task.time_limit is not None:
        lines.append(f"terminate after {task.time_limit:g} seconds")
    lines += [f"record {'' if r.when == 'step' else r.when + ' '}{format_term(r.expr)} as {r.name}  [line {r.line}]"
              for r in task.records]
    return lines
