"""The abstract syntax tree of a .prs file: frozen dataclasses, each with its source span.

The parser knows no semantics: names are unresolved, `deg` is still a postfix operator,
`(a, b)` is still a pair. prsc/ir gives these meaning.
"""

from __future__ import annotations

from dataclasses import dataclass, field

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


# ---------------------------------------------------------------- specifiers


@dataclass(frozen=True)
class Specifier(Node):
    """Base of specifiers."""


@dataclass(frozen=True)
class WithSpec(Specifier):
    """`with prop value`."""

    prop: str
    prop_span: Span
    value: Expr


@dataclass(frozen=True)
class JointSpec(Specifier):
    """`with joint "NAME" value`: a joint's starting value (docs/assets.md)."""

    joint: str
    joint_span: Span
    value: Expr


@dataclass(frozen=True)
class AtSpec(Specifier):
    """`at point`."""

    point: Expr


@dataclass(frozen=True)
class InSpec(Specifier):
    """`[completely] in region`."""

    region: Expr
    completely: bool


@dataclass(frozen=True)
class OnSpec(Specifier):
    """`[completely] on target`."""

    target: Expr
    completely: bool


@dataclass(frozen=True)
class DirectionSpec(Specifier):
    """`left of X [by d]` and its siblings; relation is left/right/ahead/behind/above/below."""

    relation: str
    target: Expr
    by: Expr | None


@dataclass(frozen=True)
class BeyondSpec(Specifier):
    """`beyond target by amount from origin`."""

    target: Expr
    by: Expr
    origin: Expr


@dataclass(frozen=True)
class AlignedSpec(Specifier):
    """`aligned with target on axis` (axis written as a name or a string)."""

    target: Expr
    axis: str
    axis_span: Span


@dataclass(frozen=True)
class FacingSpec(Specifier):
    """`facing direction`."""

    direction: Expr


@dataclass(frozen=True)
class FacingTowardSpec(Specifier):
    """`facing toward target`."""

    target: Expr


@dataclass(frozen=True)
class ReachableSpec(Specifier):
    """`reachable by robot`."""

    robot: Expr


@dataclass(frozen=True)
class StablySpec(Specifier):
    """`stably on target`."""

    target: Expr


@dataclass(frozen=True)
class VisibleSpec(Specifier):
    """`[not] visible from camera`."""

    camera: Expr
    negated: bool


# ---------------------------------------------------------------- statements


@dataclass(frozen=True)
class Statement(Node):
    """Base of statements."""


@dataclass(frozen=True)
class ImportFrom(Statement):
    """`from module import *`."""

    module: str
    module_span: Span


@dataclass(frozen=True)
class ImportModule(Statement):
    """`import module`."""

    module: str
    module_span: Span


@dataclass(frozen=True)
class Assign(Statement):
    """`name = value`."""

    target: str
    target_span: Span
    value: Expr


@dataclass(frozen=True)
class ObjectStmt(Statement):
    """`[name =] Class spec, spec, ...`; name is None for an anonymous object."""

    name: str | None
    name_span: Span | None
    class_name: str
    class_span: Span
    specifiers: tuple[Specifier, ...]


@dataclass(frozen=True)
class ParamStmt(Statement):
    """`param name = value, ...`."""

    items: tuple[tuple[str, Span, Expr], ...]


@dataclass(frozen=True)
class RequireStmt(Statement):
    """`require cond` / `require[p] cond`."""

    condition: Expr
    probability: Expr | None


@dataclass(frozen=True)
class GoalStmt(Statement):
    """`goal EXPR [for T seconds]`."""

    condition: Expr
    hold: Expr | None


@dataclass(frozen=True)
class FailStmt(Statement):
    """`fail "LABEL" when EXPR`."""

    label: str
    label_span: Span
    condition: Expr


@dataclass(frozen=True)
class TerminateStmt(Statement):
    """`terminate after T seconds`."""

    seconds: Expr


@dataclass(frozen=True)
class RecordStmt(Statement):
    """`record [initial|final] EXPR as NAME`; when is "initial", "final" or "step"."""

    when: str
    value: Expr
    name: str
    name_span: Span


@dataclass(frozen=True)
class ExprStmt(Statement):
    """A bare expression: a docstring, or a class name (an object with no specifiers)."""

    value: Expr


@dataclass(frozen=True)
class ClassProperty(Node):
    """`prop: default` inside a class body."""

    name: str
    value: Expr


@dataclass(frozen=True)
class ClassSpecifier(Node):
    """`facing: value` inside a class body: a default orientation specifier."""

    word: str
    value: Expr


@dataclass(frozen=True)
class ClassDef(Statement):
    """`class Name(Parent):` with its property lines."""

    name: str
    name_span: Span
    parent: str | None
    parent_span: Span | None
    properties: tuple[ClassProperty, ...]
    specifiers: tuple[ClassSpecifier, ...] = ()


@dataclass(frozen=True)
class ForLoop(Statement):
    """`for var in range(args):` with its indented body (unrolled by prsc/ir)."""

    var: str
    var_span: Span
    function: str  # the name called after `in` (the front end accepts only `range`)
    function_span: Span
    args: tuple[Expr, ...]
    body: tuple[Statement, ...]


@dataclass(frozen=True)
class Module(Node):
    """A whole file."""

    path: str
    statements: tuple[Statement, ...]
    source: str = field(default="", repr=False, compare=False)  # the file's text, for quoting spans
