"""Sequential scene sampling: objects in dependency order, each uniform on its feasible
region given the objects before it (docs/sampling.md, "The law of a scene"), never colliding.

Per object: the region of its rules (regions.py); placed objects whose boxes could reach
it are the only collision candidates (AABB broad phase). With no candidates and no
rejection-checked require, the first draw is accepted. Otherwise draws are rejected
against the candidates (exact OBB test); if acceptance stays low the region minus the
candidates' Minkowski obstacles is decomposed exactly into convex pieces (an empty
decomposition proves a dead end). Rejection within one object keeps its draw exactly
uniform on the free part of its region. Cells the centre must stay out of (`not visible
from C`: ObjectPlan.exclusions) are obstacles too; the exact method always decomposes them
away (no rejection), hit-and-run rejects draws inside them.

A dead end (empty region, or no free position) retries the object's own random values a
few times, then backtracks to the latest earlier object it depends on or collided with,
a bounded number of times, then restarts the scene; after a bounded number of restarts
the scene fails with the rejection statistics (never a hang).

`sweeps > 0` gives the joint law without rejection: Metropolis-within-Gibbs sweeps over
the sequential sample (gibbs.py). `joint=True` (the path `rejection`) gives the joint law by rejection instead:
objects are drawn from their regions ignoring collisions and rejection-checked requires,
and the whole scene is rejected if any pair collides or any require fails. (Exact for the
joint law when each object's region measure does not depend on earlier placements, as
with `on`; see docs.)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from prsc.constraints.context import SceneContext
from prsc.constraints.diagnostics import numeric_failure
from prsc.constraints.polytope_ir import COLLISION, CONTAINMENT, DEAD_END, REQUIRE, ConstraintProgram, RequireCheck
from prsc.constraints.values import ObjectValue
from prsc.errors import PrscError
from prsc.geometry.exceptions import EmptyRegionError, GeometryError, UnboundedRegionError
from prsc.geometry.free_space import free_space_sampler
from prsc.geometry.polytope import Polytope
from prsc.geometry.uniform_sampling import UniformSampler
from prsc.sampling.attempt import Attempt, Limits
from prsc.sampling.collisions import PlacedBox, aabb_reach, first_hit, inscribed_half, near, obstacles_for
from prsc.sampling.dead_ends import dead_end_error
from prsc.sampling.gibbs import GibbsSweeps
from prsc.sampling.proposal import Proposal
from prsc.sampling.prepared import Prepared
from prsc.sampling.runtime import ObjectRuntime, build_runtimes, draw_soft_requires, evaluate_params, inside_any
from prsc.sampling.seeds import scene_rng
from prsc.sampling.stats import RejectionStats


@dataclass
class SceneResult:
    """A sampled scene: objects in declaration order, parameter values, rejection counts."""

    objects: list[ObjectValue]
    params: dict[str, Any]
    stats: RejectionStats
    # The scene's final evaluation context (draws, objects): lets `prsc explain` rebuild rows.
    context: SceneContext | None = None


class SequentialSampler:
    """Exact (or hit-and-run) sequential placement of one compiled spec."""

    def __init__(
        self,
        cprog: ConstraintProgram,
        method: str = "exact",
        walk_length: int = 100,
        joint: bool = False,
        limits: Limits | None = None,
        proposal: Proposal | None = None,
        sweeps: int = 0,
    ) -> None:
        if method not in ("exact", "hit-and-run"):
            raise ValueError(f"unknown method {method!r}")
        self.cprog = cprog
        self.method = method
        self.walk_length = int(walk_length)
        self.joint = joint
        self.limits = limits or Limits()
        # A falsification proposal (prsc/sampling/proposal.py): reweights region and range draws.
        self.proposal = proposal
        self.runtimes = build_runtimes(cprog)
        self.index_of = {rt.plan.name: rt.plan.index for rt in self.runtimes}
        # Requires checked by rejection, per object (the object they are checked after).
        self.checks: list[tuple[RequireCheck, ...]] = [rt.plan.checks for rt in self.runtimes]
        self._declarations = {rt.plan.name: rt.plan.span for rt in self.runtimes}
        # Per object: the earlier objects its rows read (dependencies, anchor, the objects
        # its specifiers and requires name), and whether re-placing an object can change it.
        self.reads = [self._objects_read(rt) for rt in self.runtimes]
        self.movable = [
            rt.plan.static_position is None or rt.half is None or rt.rotation is None for rt in self.runtimes
        ]
        self._free_cache: dict[tuple[int, tuple[int, ...]], UniformSampler | None] = {}
        # The joint law without rejection: Gibbs sweeps over the sequential sample (gibbs.py).
        # Never with a proposal: the sweeps' ratios assume the spec's own uniform draws.
        self.gibbs = GibbsSweeps(self, sweeps) if sweeps > 0 and not joint and proposal is None else None

    # ------------------------------------------------------------ scenes
    def sample(self, seed: int, index: int) -> SceneResult:
        """Scene `index` under `seed`; PrscError if it cannot be sampled within the limits."""
        ctx = SceneContext(scene_rng(seed, index))
        if self.proposal is not None and self.method == "exact":
            ctx.proposal = self.proposal.scene_state(index)
        run = Attempt(ctx, RejectionStats(scenes=1), self.limits)
        attempts = self.limits.joint_attempts if self.joint else self.limits.scene_attempts
        tried = 0  # the work budget may end the attempts early: the message says how many ran
        for _ in range(attempts):
            if run.over_budget():
                break
            tried += 1
            ctx.rollback(-1)
            ctx.objects.clear()
            ctx.level = -1
            ctx.active_requires = draw_soft_requires(self.cprog, ctx)
            if not self._scene_checks_hold(run):
                continue
            run.placed = []
            try:
                complete = self._place_all(run)
            except GeometryError as error:  # empty and unbounded regions are handled in _place
                plan = self.runtimes[ctx.level].plan
                raise numeric_failure(plan.name, plan.span, error) from error
            if not complete:
                continue
            if self.joint and not self._joint_ok(run):
                continue
            if self.gibbs is not None:
                self.gibbs.run(run)
            ctx.level = len(self.runtimes)
            params = evaluate_params(self.cprog, ctx)
            objects = [ctx.objects[rt.plan.name] for rt in self.runtimes]
            return SceneResult(objects, params, run.stats, ctx)
        raise dead_end_error(self.cprog.labels, [rt.plan for rt in self.runtimes], self._declarations,
                             f"could not sample scene {index} (seed {seed}) in {tried} attempts; rejections: {run.stats.summary()}",
                             run.failure)

    def _scene_checks_hold(self, run: Attempt) -> bool:
        for check in self.cprog.scene_checks:
            if (check.soft is None or check.soft in run.ctx.active_requires) and not check.test(run.ctx):
                run.stats.add(REQUIRE)
                run.fail("require", -1, label=check.label_id)
                return False
        return True

    def _place_all(self, run: Attempt) -> bool:
        n = len(self.runtimes)
        k = 0
        backtracks = 0
        while k < n:
            if run.over_budget():
                return False
            run.blame = set()
            if self._place(k, run):
                k += 1
                continue
            backtracks += 1
            if backtracks > self.limits.backtracks:
                return False
            j = self._backtrack_target(k, run.blame)
            if j < 0:
                return False
            for i in range(j, k + 1):
                run.ctx.objects.pop(self.runtimes[i].plan.name, None)
            run.placed[:] = [q for q in run.placed if q.index < j]
            run.ctx.rollback(j)
            k = j
        return True

    def _backtrack_target(self, k: int, blame: set[int]) -> int:
        """The latest earlier object worth re-placing (random, and implicated), or -1."""
        # Objects it collided with are the likeliest culprits; then what its region reads.
        for group in (blame, self.reads[k]):
            for i in sorted(group, reverse=True):
                if i < k and self.movable[i]:
                    return i
        return -1

    def _objects_read(self, rt: ObjectRuntime) -> set[int]:
        plan = rt.plan
        names = set(plan.depends_on)
        if plan.region.anchor is not None:
            names.add(plan.region.anchor)
        for label_id in [r.label_id for r in plan.region.rules + plan.exclusions] + [c.label_id for c in plan.checks]:
            names.update(self.cprog.labels[label_id].refs)
        return {self.index_of[n] for n in names if n in self.index_of}

    # ------------------------------------------------------------ one object
    def _place(self, k: int, run: Attempt) -> bool:
        rt = self.runtimes[k]
        ctx = run.ctx
        ctx.level = k
        for _ in range(self.limits.object_attempts):
            if run.over_budget():
                return False
            run.placements += 1
            ctx.rollback(k)
            journal_before = len(ctx.journal)
            obj, half, support = rt.new_value(ctx)
            try:
                region, shift = rt.provider.region(ctx, support, rt.support is not None)
            except EmptyRegionError as error:
                run.stats.add(DEAD_END)
                run.fail("empty", k)
                rows = getattr(error, "rows", None)
                run.failure.rows = rows if rows is not None else rt.provider.rows(ctx, support)
                if len(ctx.journal) == journal_before:
                    return False  # nothing of its own is random: only earlier objects can help
                continue
            except UnboundedRegionError as error:
                raise PrscError(
                    f"the region of {rt.plan.name} is unbounded: add a workspace or a bounding specifier", rt.plan.span
                ) from error
            if self.draw_position(rt, obj, half, region, shift, rt.excluded(ctx, support), run):
                rt.finish(obj, ctx)
                run.placed.append(rt.placed_box(obj, half, ctx))
                return True
            if len(ctx.journal) == journal_before and run.failure.kind == "blocked":
                return False  # proven: no free position, and nothing of its own to redraw
        return False

    def _blocked(self, rt: ObjectRuntime, candidates: list[PlacedBox], run: Attempt) -> bool:
        """Record that no free position exists among `candidates`; always False."""
        run.stats.add(DEAD_END)
        run.fail("blocked", rt.plan.index, list(candidates))
        run.blame.update(q.index for q in candidates)
        return False

    def draw_position(
        self, rt: ObjectRuntime, obj: ObjectValue, half: np.ndarray, region: Prepared, shift: np.ndarray | None,
        excluded: list[Polytope], run: Attempt,
    ) -> bool:
        """Draw the object's position (and late rotation) outside the `excluded` cells; True when accepted."""
        ctx = run.ctx
        rng = ctx.rng
        method = self.method
        reach = rt.reach
        if reach is None:
            mode = "exact" if obj.rotation is not None else rt.plan.orientation.bound_mode  # type: ignore[union-attr]
            reach = aabb_reach(obj.rotation, half, mode)
        allow = not self.joint and rt.allows_collisions(obj, ctx)
        candidates: list[PlacedBox] = []
        if run.placed and not self.joint and not allow:
            lo, hi = (region.lo, region.hi) if shift is None else (region.lo + shift, region.hi + shift)
            candidates = near(run.placed, lo, hi, reach, containers=rt.plan.rests_in)
        checks = () if self.joint else tuple(c for c in rt.plan.checks if c.soft is None or c.soft in ctx.active_requires)
        if not candidates and not checks and not excluded:
            p = self._region_draw(rt, region, run)
            obj.position = p if shift is None else p + shift
            rt.late_rotation(obj, ctx)
            return True
        if (candidates or excluded) and shift is None and not rt.after_position and method == "exact" \
                and rt.static_exclusions and self._all_static(rt, region, candidates):
            # Region and obstacles are the same every scene: decompose the free space once.
            free = self._static_free_space(rt, region, candidates, obj.rotation, half, excluded)  # type: ignore[arg-type]
            if free is None:
                return self._blocked(rt, candidates, run)
            # The pieces are exactly the collision-free positions (the obstacles' interiors
            # are where the OBB test says "collides"): only requires can reject a draw.
            for _ in range(self.limits.free_draws):
                if self._accept(rt, obj, half, self._free_draw(rt, free, region, candidates, obj.rotation, half, run),
                                [], checks, run):
                    return True
            return False
        # The exact method never draws inside an excluded cell (it decomposes them away below),
        # and seeks by rejection only as long as that is cheaper than the decomposition.
        if method != "exact":
            rejection_draws = self.limits.point_draws
        else:
            rejection_draws = 0 if excluded else self.limits.exact_point_draws
        for _ in range(rejection_draws):
            run.draws += 1
            if run.draws > self.limits.draw_budget:
                return False
            p = self._region_draw(rt, region, run)
            if self._accept(rt, obj, half, p if shift is None else p + shift, candidates, checks, run, excluded):
                return True
        if not (candidates or excluded) or method != "exact":
            return False
        # Low acceptance against the placed boxes: decompose the free space exactly. With a
        # rotation still unknown (`facing toward`), subtract what collides for every yaw
        # (the obstacles of a box inscribed in the footprint): a superset of the free
        # space, from which rejection is still exactly uniform, and empty only if there
        # is no free position at all.
        if rt.after_position:
            mode = rt.plan.orientation.bound_mode  # type: ignore[union-attr]
            rotation, obstacle_half = np.eye(3), inscribed_half(half, mode)
        else:
            rotation, obstacle_half = obj.rotation, half
        try:
            free = region.free_space(shift, obstacles_for(candidates, rotation, obstacle_half), excluded)  # type: ignore[arg-type]
        except EmptyRegionError:
            return self._blocked(rt, candidates, run)
        if ctx.proposal is not None:
            ctx.proposal.spec_position(rt.plan.name, rt.plan.index)
        for _ in range(self.limits.free_draws):
            run.draws += 1
            if self._accept(rt, obj, half, free.sample_one(rng), candidates, checks, run):
                return True
        return False

    def _region_draw(self, rt: ObjectRuntime, region: Prepared, run: Attempt) -> np.ndarray:
        """A position on the region: the spec's law, or the falsification proposal's (ratio recorded)."""
        if run.ctx.proposal is None:
            return region.draw(run.ctx.rng, self.method, self.walk_length)
        return run.ctx.proposal.position(rt.plan.name, rt.plan.index, region, run.ctx)

    def _free_draw(self, rt: ObjectRuntime, free: UniformSampler, region: Prepared, candidates: list[PlacedBox],
                   rotation: np.ndarray, half: np.ndarray, run: Attempt) -> np.ndarray:
        """A position on the static free space: the spec's law, or the falsification proposal's (ratio recorded)."""
        if run.ctx.proposal is None:
            return free.sample_one(run.ctx.rng)
        obstacles = obstacles_for(candidates, rotation, half)
        return run.ctx.proposal.free_position(rt.plan.name, rt.plan.index, free, region, obstacles, run.ctx)

    def _all_static(self, rt: ObjectRuntime, region: Prepared, candidates: list[PlacedBox]) -> bool:
        """Whether the region and every candidate obstacle are the same objects in every scene."""
        return region is rt.provider.static_prepared and rt.support is not None and all(
            q is self.runtimes[q.index].static_box for q in candidates
        )

    def _static_free_space(
        self, rt: ObjectRuntime, region: Prepared, candidates: list[PlacedBox], rotation: np.ndarray, half: np.ndarray,
        excluded: list[Polytope],
    ) -> UniformSampler | None:
        """Exact sampler of the static region minus static obstacles and excluded cells (cached); None if nothing is free."""
        key = (rt.plan.index, tuple(q.index for q in candidates))
        if key not in self._free_cache:
            try:
                obstacles = obstacles_for(candidates, rotation, half) + excluded
                free: UniformSampler | None = free_space_sampler(region.poly, obstacles)
            except EmptyRegionError:
                free = None
            self._free_cache[key] = free
        return self._free_cache[key]

    def _accept(
        self, rt: ObjectRuntime, obj: ObjectValue, half: np.ndarray, position: np.ndarray,
        candidates: list[PlacedBox], checks: tuple[RequireCheck, ...], run: Attempt, excluded: Sequence[Polytope] = (),
    ) -> bool:
        if inside_any(excluded, position):
            run.stats.add(CONTAINMENT)  # hit-and-run only: exact draws come from outside the cells
            run.fail("blocked", rt.plan.index, [])
            return False
        obj.position = position
        rt.late_rotation(obj, run.ctx)
        assert obj.rotation is not None
        if candidates:
            reach = aabb_reach(obj.rotation, half) if rt.after_position or rt.reach is None else rt.reach
            hit = first_hit(candidates, position, obj.rotation, half, reach)
            if hit is not None:
                run.stats.add(COLLISION)
                run.blame.add(hit.index)
                run.fail("blocked", rt.plan.index, [hit])
                return False
        for check in checks:
            if not check.test(run.ctx):
                run.stats.add(REQUIRE)
                run.fail("require", rt.plan.index, label=check.label_id)
                return False
        return True

    # ------------------------------------------------------------ joint law
    def _joint_ok(self, run: Attempt) -> bool:
        """Whole-scene test: no pair collides and every rejection-checked require holds."""
        placed = run.placed
        for i, q in enumerate(placed):
            if q.allow:
                continue
            others = near(placed[:i], np.array(q.center), np.array(q.center), q.reach,
                          containers=self.runtimes[q.index].plan.rests_in)
            hit = first_hit(others, q.box.center, q.box.rotation, q.box.half_extents, q.reach)
            if hit is not None:
                run.stats.add(COLLISION)
                run.fail("blocked", q.index, [hit])
                return False
        for checks in self.checks:
            for check in checks:
                if (check.soft is None or check.soft in run.ctx.active_requires) and not check.test(run.ctx):
                    run.stats.add(REQUIRE)
                    run.failure.kind, run.failure.label = "require", check.label_id
                    return False
        return True
