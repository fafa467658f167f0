"""What lowering one program accumulates: compiled expressions, static facts, row labels."""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from prsc.constraints.context import SceneContext
from prsc.constraints.evaluate import ExprCompiler, StaticFacts
from prsc.constraints.polytope_ir import RowLabel
from prsc.constraints.values import ObjectValue, static_dims
from prsc.errors import Span
from prsc.ir.program import Program


@lru_cache(maxsize=32)
def _lines(text: str) -> tuple[str, ...]:
    """A source file's lines, split once per file (labels ask for many spans of the same file)."""
    return tuple(text.splitlines())


def source_text(program: Program, span: Span | None, fallback: str = "") -> str:
    """The source text a span covers, on one line (whitespace collapsed), from the IR's own copy of the files."""
    if span is None:
        return fallback
    text = next((text for path, text in program.sources if path == span.path), None)
    if text is None:
        return fallback
    lines = _lines(text)
    if span.line > len(lines):
        return fallback
    if span.end_line == span.line:
        covered = lines[span.line - 1][span.column - 1 : span.end_column - 1]
    else:
        parts = [lines[span.line - 1][span.column - 1 :]]
        parts += lines[span.line : span.end_line - 1]
        if span.end_line <= len(lines):
            parts.append(lines[span.end_line - 1][: span.end_column - 1])
        covered = " ".join(parts)
    return " ".join(covered.split()) or fallback


class LoweringState:
    """State while lowering one program."""

    def __init__(self, program: Program) -> None:
        self.program = program
        self.facts = StaticFacts()
        self.compiler = ExprCompiler(program, self.facts)
        self.labels: list[RowLabel] = []
        self.index_of = {obj.name: i for i, obj in enumerate(program.objects)}
        self.declarations = {obj.name: obj.span for obj in program.objects}

    def label(self, obj: str, text: str, span: Span | None, cause: str, refs: tuple[str, ...] = ()) -> int:
        """Register a row label; returns its id."""
        self.labels.append(RowLabel(obj, text, span, cause, tuple(r for r in refs if r != obj)))
        return len(self.labels) - 1

    def fixed_context(self, me: ObjectValue, anchor: str | None = None) -> SceneContext:
        """What a row template's arguments read: the objects fixed at compile time, the object
        being lowered, and the anchor (rotation and size fixed) at the origin.

        Only arguments the analyses found constant or moving with the anchor are evaluated
        in it, so nothing asks it for a random draw."""
        ctx = SceneContext(None)  # type: ignore[arg-type]
        ctx.objects.update(self.facts.objects)
        ctx.objects[me.name] = me
        if anchor is not None:
            facts = self.facts
            decl = self.program.objects[self.index_of[anchor]]
            ctx.objects[anchor] = ObjectValue(anchor, decl.class_name, decl.span, np.zeros(3), facts.rotations[anchor],
                                              static_dims(facts.props[anchor]), dict(facts.props[anchor]))
        return ctx

    def text(self, span: Span | None, fallback: str) -> str:
        """The source text of a span."""
        return source_text(self.program, span, fallback)
