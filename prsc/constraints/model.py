"""The polytope constraint IR: what the sampler consumes.

Per object: its property closures, its orientation rule, and its position rules. A
position rule turns the concrete values of one scene (earlier objects, draws) into
labelled rows `A p <= b`, `C p = d` on the object's centre p; every row's integer label
indexes ConstraintProgram.labels, which remembers the specifier text and source span.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from prsc.constraints.context import SceneContext
from prsc.constraints.values import ObjectValue
from prsc.errors import Span
from prsc.geometry.boxes import support as box_support
from prsc.geometry.polytope import Polytope
from prsc.ir import model as ir

# Rejection causes, as in the paper's Table II (plus require and the exact sampler's
# proven dead ends).
COLLISION = "collision"
RELATIVE = "relative position"
CONTAINMENT = "containment"
REQUIRE = "require"
POSITION = "position"
DEAD_END = "dead end"
CAUSES = (COLLISION, RELATIVE, CONTAINMENT, REQUIRE)


@dataclass(frozen=True)
class RowLabel:
    """Where rows came from: the object, the specifier's text and span, a rejection cause."""

    object: str
    text: str
    span: Span | None
    cause: str
    # Other objects the specifier refers to (names), to point at their declarations.
    refs: tuple[str, ...] = ()


class Support:
    """The support function s(n) of the object's box about its centre (LANGUAGE.md section 4).

    mode "exact": rotation known; "yaw": rotation is an unknown yaw (facing toward), so
    use the footprint's radius horizontally (exact vertically); "free": rotation unknown,
    use the box's circumradius.
    """

    __slots__ = ("rotation", "half", "mode", "_radius_xy", "_radius")

    def __init__(self, rotation: np.ndarray | None, half_extents: np.ndarray, mode: str = "exact") -> None:
        self.rotation = rotation
        self.half = np.asarray(half_extents, dtype=float)
        self.mode = mode
        self._radius_xy = float(np.hypot(self.half[0], self.half[1]))
        self._radius = float(np.linalg.norm(self.half))

    def __call__(self, normals: np.ndarray) -> np.ndarray:
        """s(n) for each row of normals (m, 3); positively homogeneous in n."""
        n = np.asarray(normals, dtype=float)
        if self.mode == "exact":
            return box_support(self.rotation, self.half, n)
        if self.mode == "yaw":
            return np.abs(n[..., 2]) * self.half[2] + np.hypot(n[..., 0], n[..., 1]) * self._radius_xy
        return np.linalg.norm(n, axis=-1) * self._radius

    def key(self) -> tuple:
        """A hashable summary (for region caches)."""
        rot = None if self.rotation is None else self.rotation.tobytes()
        return (self.mode, rot, self.half.tobytes())


BuildRows = Callable[[SceneContext, Support], Polytope]


@dataclass(frozen=True)
class PositionRule:
    """One specifier (or lowered require, or the workspace) as rows on p.

    `static` rules do not change between scenes (given the object's static size and
    rotation); `rows` holds their rows, built once. `soft` is the index of a soft
    require this rule enforces only in scenes where it is active.
    """

    label_id: int
    static: bool
    build: BuildRows
    rows: Polytope | None = None
    soft: int | None = None


@dataclass(frozen=True)
class OrientationRule:
    """How the object's rotation is computed; `after_position` for `facing toward` etc."""

    label_id: int
    after_position: bool
    bound_mode: str  # Support mode to use for erosion while the rotation is unknown
    compute: Callable[[SceneContext, ObjectValue], np.ndarray]
    static_value: np.ndarray | None = None


@dataclass(frozen=True)
class RequireCheck:
    """A require checked by rejection once every object it mentions is placed."""

    label_id: int
    test: Callable[[SceneContext], bool]
    soft: int | None = None


@dataclass(frozen=True)
class RegionRules:
    """The rules whose intersection is an object's region, pre-digested for caching.

    `static_rows`: the static rules stacked (None if none). When every non-static rule
    depends on the scene only through the position t of one earlier object (`anchor`)
    and moves rigidly with it (e.g. `on tr_1`), `anchored_rows` holds those rules' rows
    with the anchor at the origin: the scene's rows are anchored_rows translated by t.
    """

    rules: tuple[PositionRule, ...]
    static_rows: Polytope | None = None
    anchor: str | None = None
    anchored_rows: Polytope | None = None

    @property
    def dynamic(self) -> tuple[PositionRule, ...]:
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
    property_fns: dict[str, Callable[[SceneContext], Any]]
    static_props: dict[str, Any]
    orientation: OrientationRule | None
    # Every position rule (specifiers, workspace, lowered requires): the exact region.
    region: RegionRules
    # Requires on this object that are not linear: checked by rejection.
    checks: tuple[RequireCheck, ...]
    depends_on: tuple[str, ...]
    # The rejection baseline's draw region: equalities and `on` surfaces (no erosion), in
    # the workspace's bounding box; it then tests every rule of `region`.
    base_region: RegionRules | None = None
    static_position: np.ndarray | None = None

    @property
    def rules(self) -> tuple[PositionRule, ...]:
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

    program: ir.Program
    objects: tuple[ObjectPlan, ...]
    labels: tuple[RowLabel, ...]
    # Requires that mention no object: checked once per scene before placing objects.
    scene_checks: tuple[RequireCheck, ...]
    soft_requires: tuple[SoftRequire, ...]
    params: tuple[tuple[str, Callable[[SceneContext], Any]], ...]
    # Every require as a plain test (what the rejection baseline checks), with the index
    # of the object after which it can be evaluated (-1: before any object).
    require_tests: tuple[tuple[int, RequireCheck], ...] = field(default=())
    # Label ids of lowered requires, by the object they were lowered onto (for explain).
    lowered_requires: dict[str, tuple[int, ...]] = field(default_factory=dict)
