"""The typed IR's program: classes, objects, variables, params and requirements of a spec.

The nodes a whole spec compiles to (prsc/ir/model.py holds the expressions and specifiers
they carry); same contract as there: frozen dataclasses with their source spans.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from prsc.errors import Span
from prsc.ir.model import Expr, Specifier
from prsc.task.terms import TaskStatements


@dataclass(frozen=True)
class ClassDef:
    """A class with its parent chain flattened: every property with its default expression.

    Defaults here are templates (they may contain SelfRef); objects carry instantiated copies.
    """

    name: str
    parent: str | None
    defaults: tuple[tuple[str, Expr], ...]
    span: Span
    # Default orientation specifiers (`facing: yaw` in the body), inherited; an object's
    # own orientation specifier replaces them.
    specifiers: tuple[Specifier, ...] = ()


@dataclass(frozen=True)
class SelfRef(Expr):
    """`self.prop` inside a class default (only in ClassDef templates, never in objects)."""

    prop: str


@dataclass(frozen=True)
class ObjectDecl:
    """One scene object with its instantiated properties and ordered specifiers."""

    name: str
    class_name: str
    anonymous: bool
    span: Span
    # Every property's defining expression after class defaults and `with` overrides,
    # excluding position and orientation (those come from specifiers).
    properties: tuple[tuple[str, Expr], ...]
    # Specifiers in evaluation order (topological over sets/reads).
    specifiers: tuple[Specifier, ...]
    # Names of scene objects this one depends on (all earlier in Program.objects).
    depends_on: tuple[str, ...] = ()
    # The class and its ancestors, most derived first, ending with "Object" (front end addition).
    class_chain: tuple[str, ...] = ()

    def prop(self, name: str) -> Expr | None:
        """The defining expression of a property, or None."""
        return dict(self.properties).get(name)


@dataclass(frozen=True)
class Variable:
    """`x = expr` at top level (not an object)."""

    name: str
    value: Expr
    span: Span


@dataclass(frozen=True)
class Param:
    """`param name = expr`: written to every output's metadata."""

    name: str
    value: Expr
    span: Span


@dataclass(frozen=True)
class Require:
    """`require expr` (probability 1) or `require[p] expr` (soft)."""

    condition: Expr
    probability: float
    span: Span


@dataclass(frozen=True)
class TaskLinkRef:
    """`X.links["NAME"]` in a task statement (docs/tasks.md): object X, link NAME, where it is written,
    and the relation it is the target of ("in", "completely on"; None: `touches`, `distance from`)."""

    obj: str
    link: str
    span: Span
    relation: str | None = None


@dataclass(frozen=True)
class Program:
    """A whole spec after imports, name resolution and type checking."""

    path: str
    objects: tuple[ObjectDecl, ...]  # in dependency order: every object after those it reads
    variables: tuple[Variable, ...]  # in definition order
    params: tuple[Param, ...]
    requires: tuple[Require, ...]
    workspace: Expr | None  # a REGION expression, or None for All()
    classes: tuple[ClassDef, ...] = field(default=())
    source_files: tuple[str, ...] = field(default=())  # the spec and every imported file
    # (path, text) of every file read, so later stages quote source text as it was compiled.
    sources: tuple[tuple[str, str], ...] = field(default=(), repr=False, compare=False)
    task: TaskStatements = field(default_factory=TaskStatements)  # docs/tasks.md
    # every `X.links["NAME"]` the task names, read from X's file by ir/asset_models.py into task.links
    task_links: tuple[TaskLinkRef, ...] = field(default=())
