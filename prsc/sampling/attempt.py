"""The state of sampling one scene, and the bounds that make every failure finite."""

from __future__ import annotations

from dataclasses import dataclass, field

from prsc.constraints.context import SceneContext
from prsc.geometry.polytope import Polytope
from prsc.sampling.collisions import PlacedBox
from prsc.sampling.stats import RejectionStats


@dataclass(frozen=True)
class Limits:
    """Bounds that make every failure finite."""

    scene_attempts: int = 20  # whole-scene restarts
    backtracks: int = 30  # per scene attempt
    object_attempts: int = 8  # redraws of one object's own random values
    point_draws: int = 200  # rejection draws of an object (hit-and-run: all it has)
    # The exact method's rejection draws before it decomposes the free space exactly (the
    # law is the same either way). A draw with its collision tests costs 30-75 us and a
    # decomposition 2-3 ms, so rejection pays while it needs fewer than ~30 draws: with 20,
    # ten cubes on a tray sample 2x faster than with 200, bin_picking 1.2x (docs/sampling.md).
    exact_point_draws: int = 20
    free_draws: int = 50  # draws from the decomposition (only rounding or requires reject these)
    joint_attempts: int = 100_000  # whole-scene rejections under --law rejection
    # Work per scene over all restarts and backtracks: object placements tried (each may
    # prepare a region) and positions drawn. Whatever the spec, a scene ends within these.
    placement_budget: int = 2_000
    draw_budget: int = 200_000


@dataclass
class Failure:
    """What went wrong last, for the error message when a scene cannot be sampled."""

    index: int = -1
    kind: str = ""
    rows: Polytope | None = None
    blockers: list[PlacedBox] = field(default_factory=list)
    label: int = -1


@dataclass
class Attempt:
    """The state of sampling one scene: the sampler itself keeps none, so it is re-entrant.

    `blame` holds the objects the current placement collided with (backtrack candidates).
    """

    ctx: SceneContext
    stats: RejectionStats
    limits: Limits
    placed: list[PlacedBox] = field(default_factory=list)
    failure: Failure = field(default_factory=Failure)
    blame: set[int] = field(default_factory=set)
    placements: int = 0
    draws: int = 0

    def over_budget(self) -> bool:
        """Whether this scene has used up its work budget."""
        return self.placements >= self.limits.placement_budget or self.draws >= self.limits.draw_budget

    def fail(self, kind: str, index: int, blockers: list[PlacedBox] | None = None, label: int = -1) -> None:
        """Remember the latest failure (for the error message)."""
        self.failure.index, self.failure.kind = index, kind
        if blockers is not None:
            self.failure.blockers = blockers
        if label >= 0:
            self.failure.label = label
