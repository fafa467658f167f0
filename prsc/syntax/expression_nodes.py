"""The expressions of the abstract syntax tree (and the base of every node): frozen dataclasses,
each with its source span. Unresolved names, `deg` still a postfix operator, `(a, b)` still a pair."""

from __future__ import annotations

from dataclasses import dataclass

from prsc.errors import Span


@dataclass(frozen=True)
class Node:
    """Base of every AST node."""

    span: Span


# ---------------------------------------------------------------- expressions


@dataclass(frozen=True)
class Expr(Node):
    """Base of expressions."""


@dataclass(frozen=True)
class Number(Expr):
    """A numeric literal."""

    value: float


@dataclass(frozen=True)
class String(Expr):
    """A string literal (quotes removed, escapes decoded)."""

    value: str


@dataclass(frozen=True)
class Bool(Expr):
    """`True` / `False`."""

    value: bool


@dataclass(frozen=True)
class Name(Expr):
    """A bare identifier."""

    id: str


@dataclass(frozen=True)
class Attribute(Expr):
    """`target.name`."""

    target: Expr
    name: str
    name_span: Span


@dataclass(frozen=True)
class Index(Expr):
    """`target[index]` (a support surface of a list, as in `shelf.boards[1]`)."""

    target: Expr
    index: Expr


@dataclass(frozen=True)
class Call(Expr):
    """`func(arg, ...)`."""

    func: Expr
    args: tuple[Expr, ...]


@dataclass(frozen=True)
class Pair(Expr):
    """`(a, b)`: a parenthesised pair (a uniform range, compat)."""

    low: Expr
    high: Expr


@dataclass(frozen=True)
class ListLit(Expr):
    """`[a, b, ...]`."""

    items: tuple[Expr, ...]


@dataclass(frozen=True)
class DictLit(Expr):
    """`{k: v, ...}`."""

    items: tuple[tuple[Expr, Expr], ...]


@dataclass(frozen=True)
class BinOp(Expr):
    """`left op right` for + - * /."""

    op: str
    left: Expr
    right: Expr


@dataclass(frozen=True)
class UnaryOp(Expr):
    """`-x`, `+x`, `not x`."""

    op: str
    operand: Expr


@dataclass(frozen=True)
class Compare(Expr):
    """`a < b <= c`: a chain of comparisons."""

    left: Expr
    rest: tuple[tuple[str, Expr], ...]


@dataclass(frozen=True)
class BoolOp(Expr):
    """`a and b and c` / `a or b`."""

    op: str
    operands: tuple[Expr, ...]


@dataclass(frozen=True)
class Degrees(Expr):
    """`x deg`."""

    value: Expr


@dataclass(frozen=True)
class FacePoint(Expr):
    """`top back X`: the face words in source order, then the target."""

    words: tuple[str, ...]
    target: Expr
    words_closed: bool = False  # written in brackets: `top (back t)` does not merge words


@dataclass(frozen=True)
class Distance(Expr):
    """`distance from source to target` (docs/language.md, "distance from X to Y")."""

    source: Expr
    target: Expr


@dataclass(frozen=True)
class RelativeTo(Expr):
    """`value relative to frame`."""

    value: Expr
    frame: Expr


@dataclass(frozen=True)
class Relation(Expr):
    """A relation or state word of a task statement (docs/tasks.md), on the simulated state.

    kind: in, on, left, right, ahead, behind, above, below, touches, holds, at_rest, upright, visible."""

    kind: str
    subject: Expr
    target: Expr | None
    completely: bool = False
    by: Expr | None = None
    word_span: Span | None = None
