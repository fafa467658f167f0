"""The polytope constraint IR: what the sampler consumes, as data.

Per object: its property evaluators, its orientation rule and its position rules. A
position rule is a frozen record: its kind, its arguments as IR expressions, its label
(specifier text and source span) and, when the compiler can tell, its row template: the
rows `A p <= b`, `C p = d` on the object's centre p with every other object it reads at
the origin, and the one object (`anchor`) whose position moves them (None: the rows are
the same in every scene). Analyses (analysis.py) and row building (build.py) are plain
functions over these records.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from prsc.constraints.context import SceneContext
from prsc.constraints.support import Support
from prsc.errors import Span
from prsc.geometry.polytope import Polytope
from prsc.ir import model as ir
from prsc.ir.program import Program

# Rejection causes, as in the paper's Table II (plus require and the exact sampler's
# proven dead ends).
COLLISION = "collision"
RELATIVE = "relative position"
CONTAINMENT = "containment"
REQUIRE = "require"
POSITION = "position"
DEAD_END = "dead end"
CAUSES = (COLLISION, RELATIVE, CONTAINMENT, REQUIRE)

# Rule kinds whose rows are a cell the centre must stay out of (ObjectPlan.exclusions):
# `not visible from C`, and the hole about a robot's base and the gap behind it that
# `reachable by R` excludes.
EXCLUSION_KINDS = frozenset({"not visible", "unreachable"})

Evaluator = Callable[[SceneContext], Any]


@dataclass(frozen=True)
class RowLabel:
    """Where rows came from: the object, the specifier's text and span, a rejection cause."""

    object: str
    text: str
    span: Span | None
    cause: str
    # Other objects the specifier refers to (names), to point at their declarations.
    refs: tuple[str, ...] = ()


@dataclass(frozen=True, eq=False)
class RowTemplate:
    """A rule's rows with the object `anchor` at the origin; anchor None: the rows of every scene.

    In a scene where the anchor's centre is t the rows are these translated by t
    (`A p <= b + A t`): the rule reads nothing else that changes between scenes.
    """

    rows: Polytope
    anchor: str | None = None


@dataclass(frozen=True, eq=False)
class Rule:
    """One position rule: a specifier, the workspace, a lowered require or `reachable by`.

    `kind` names the row builder (build.py); `args` are the IR expressions it reads and
    `values` their compiled evaluators, in the same order; `options` the specifier's
    constant settings (completely, the direction word, the axis). `soft` is the index of
    a soft require this rule enforces only in scenes where it is active.
    """

    kind: str
    label_id: int
    span: Span | None
    args: tuple[ir.Expr, ...]
    options: tuple[tuple[str, Any], ...] = ()
    template: RowTemplate | None = None
    soft: int | None = None
    values: tuple[Evaluator, ...] = field(default=(), repr=False, compare=False)
    # `completely on X`: the same rule without erosion; `stably on X`: `on X` (what the rejection baseline draws from).
    relaxed: Rule | None = None

    def option(self, name: str, default: Any = None) -> Any:
        """The value of one option."""
        return next((value for key, value in self.options if key == name), default)

    @property
    def static(self) -> bool:
        """Whether its rows are the same in every scene."""
        return self.template is not None and self.template.anchor is None

    @property
    def rows(self) -> Polytope | None:
        """The rows of a static rule (None otherwise)."""
        return self.template.rows if self.static else None  # type: ignore[union-attr]


@dataclass(frozen=True)
class OrientationRule:
    """How the object's rotation is set: `facing`, `facing toward` or `with orientation`."""

    kind: str  # facing | facing toward | with orientation
    label_id: int
    arg: ir.Expr
    after_position: bool
    bound_mode: str  # Support mode to use for erosion while the rotation is unknown
    value: Evaluator = field(repr=False, compare=False)
    static_value: np.ndarray | None = None


@dataclass(frozen=True)
class RequireCheck:
    """A require checked by rejection once every object it mentions is placed."""

    label_id: int
    test: Callable[[SceneContext], bool] = field(repr=False, compare=False)
    soft: int | None = None


@dataclass(frozen=True)
class RegionRules:
    """The rules whose intersection is an object's region (before exclusions), pre-digested for caching.

    `static_rows`: the static rules stacked (None if none). `anchor` / `anchored_rows`:
    when every other rule has a template anchored at the same earlier object, their
    rows with that object at the origin (the scene's rows are these translated by its
    position). `point_rule`: the index of a rule fixing p to a point (`at V`), if any.
    """

    rules: tuple[Rule, ...]
    static_rows: Polytope | None = None
    anchor: str | None = None
    anchored_rows: Polytope | None = None
    point_rule: int | None = None

    @property
    def dynamic(self) -> tuple[Rule, ...]:
        """The rules rebuilt every scene."""
        return tuple(r for r in self.rules if not r.static)


@dataclass(frozen=True)
class ObjectPlan:
    """Everything needed to place one object."""

    index: int
    name: str
    class_name: str
    anonymous: bool
    span: Span
    property_fns: dict[str, Evaluator]
    static_props: dict[str, Any]
    orientation: OrientationRule | None
    # Every position rule (specifiers, workspace, lowered requires): the exact region.
    region: RegionRules
    # Requires on this object that are not linear: checked by rejection.
    checks: tuple[RequireCheck, ...]
    depends_on: tuple[str, ...]
    static_position: np.ndarray | None = None
    # The object's support function when it is the same in every scene.
    static_support: Support | None = None
    # Containers this object rests inside (`on X`, X declaring an interior): not collision obstacles.
    rests_in: tuple[int, ...] = ()
    # Rules whose rows are a convex set the centre must stay out of (`not visible from C`): the
    # object's feasible set is its region minus their union. Samplers subtract them as obstacles.
    exclusions: tuple[Rule, ...] = ()

    @property
    def rules(self) -> tuple[Rule, ...]:
        """All position rules."""
        return self.region.rules


@dataclass(frozen=True)
class SoftRequire:
    """`require[p] cond`: enforced in a fraction p of scenes."""

    index: int
    probability: float
    label_id: int


@dataclass(frozen=True)
class ConstraintProgram:
    """The whole spec lowered for sampling."""

    program: Program
    objects: tuple[ObjectPlan, ...]
    labels: tuple[RowLabel, ...]
    # Requires that mention no object: checked once per scene before placing objects.
    scene_checks: tuple[RequireCheck, ...]
    soft_requires: tuple[SoftRequire, ...]
    params: tuple[tuple[str, Evaluator], ...]
    # Every require as a plain test (what the rejection baseline checks), with the index
    # of the object after which it can be evaluated (-1: before any object).
    require_tests: tuple[tuple[int, RequireCheck], ...] = field(default=())
    # Label ids of lowered requires, by the object they were lowered onto (for explain).
    lowered_requires: dict[str, tuple[int, ...]] = field(default_factory=dict)
    # The workspace's bounding box when static (the rejection baseline draws from it).
    workspace_box: Polytope | None = None
