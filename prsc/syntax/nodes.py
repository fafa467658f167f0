"""The abstract syntax tree of a .prs file: frozen dataclasses, each with its source span;
the expressions (and the base Node) are in expression_nodes.py.

The parser knows no semantics: names are unresolved, `deg` is still a postfix operator,
`(a, b)` is still a pair. prsc/ir gives these meaning.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from prsc.errors import Span
from prsc.syntax.expression_nodes import (  # noqa: F401 - the AST's expressions, read as nodes.X too
    Node, Expr, Number, String, Bool, Name,
    Attribute, Index, Call, Pair, ListLit, DictLit,
    BinOp, UnaryOp, Compare, BoolOp, Degrees, FacePoint,
    Distance, RelativeTo, Relation,
)


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
