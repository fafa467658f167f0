"""The joint law without whole-scene rejection: Metropolis-within-Gibbs sweeps over a
sequential sample (docs/sampling.md, "The joint law").

The target is the law `--law rejection` samples: every object drawn uniform on its region
given the objects before it, conditioned on no collision and every rejection-checked
require holding, density  prod_k 1[x_k in R_k] / |R_k|  on the valid scenes.

One update re-places object k. Its dependants (the objects whose rows read it, directly or
through each other) form its group and move with it by the same translation, as a tray
carries its cubes, or (half the time) are drawn afresh from their regions given k's new
position. k's new position is drawn exactly uniform on its region minus the boxes
of every object outside the group (the engine's own draw: rejection, then the exact
free-space decomposition). The proposal is symmetric (the outside objects do not move), so
a translation is accepted with probability min(1, prod_j |R_j(old)| / |R_j(new)|) over
the dependants j (a fresh draw of them cancels those factors), and only if every dependant stays in its region, nothing collides and every
require holds. Without dependants this is an exact Gibbs draw from k's conditional.

Objects keep their own random values (sizes, pre-position rotations, colours) from the
sequential sample; only positions (and rotations that follow the position) move.
Scenes whose movable objects cannot reach one another need no update: `interacting`
detects them per scene, so they keep the sequential sampler's speed.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from prsc.constraints.support import Support
from prsc.geometry.exceptions import EmptyRegionError
from prsc.sampling.attempt import Attempt
from prsc.geometry.free_space import free_space_sampler
from prsc.sampling.collisions import PlacedBox, aabb_reach, first_hit, near, obstacles_for
from prsc.sampling.regions import Prepared, violated_rule
from prsc.sampling.runtime import ObjectRuntime

if TYPE_CHECKING:
    from prsc.sampling.engine import SequentialSampler

# Sweeps per scene, chosen from the mixing measurement in docs/sampling.md ("The joint law"):
# the per-coordinate KS distance to the rejection reference is within noise after 2 sweeps
# on the specs measured there; 4 doubles that margin.
DEFAULT_SWEEPS = 4
# A group move either translates the dependants with k (the measure ratio decides) or, with
# this probability, draws them afresh from their regions given k's new position: the
# proposal then cancels the target's 1/|R_j| factors, so only validity decides. Translation
# moves a tray with its cubes; redrawing moves cups that share a coordinate with k.
REDRAW = 0.5


def _support(rt: ObjectRuntime, rotation: np.ndarray | None, half: np.ndarray) -> Support:
    """The support function the object's region was built with (as ObjectRuntime.new_value)."""
    if rt.support is not None:
        return rt.support
    if not rt.after_position and rotation is not None:
        return Support(rotation, half, "exact")
    return Support(None, half, rt.plan.orientation.bound_mode)  # type: ignore[union-attr]


class GibbsSweeps:
    """Metropolis-within-Gibbs updates of a complete scene, in place, for one engine."""

    def __init__(self, engine: SequentialSampler, sweeps: int = DEFAULT_SWEEPS) -> None:
        self.engine = engine
        self.sweeps = int(sweeps)
        runtimes = engine.runtimes
        n = len(runtimes)
        readers: list[set[int]] = [set() for _ in range(n)]
        for j, reads in enumerate(engine._reads):
            for i in reads:
                if i != j:
                    readers[i].add(j)
        # group[k]: k and everything that reads it, transitively (all placed after k).
        self.groups: list[tuple[int, ...]] = []
        for k in range(n):
            seen, todo = {k}, [k]
            while todo:
                for j in readers[todo.pop()]:
                    if j not in seen:
                        seen.add(j)
                        todo.append(j)
            self.groups.append(tuple(sorted(seen)))
        self.movable = [k for k in range(n) if engine._movable[k]]
        self.has_checks = any(engine._checks)
        # Fresh draws of a group need every dependant's rotation before its position.
        self.redraw = [all(not engine.runtimes[j].after_position for j in g[1:]) for g in self.groups]

    # ------------------------------------------------------------ detection
    def interacting(self, run: Attempt) -> bool:
        """Whether some movable object's region reaches an object outside its group (or a
        rejection-checked require exists): otherwise the sequential sample is already exact."""
        if self.has_checks:
            return True
        ctx, boxes = run.ctx, self._boxes(run)
        for k in self.movable:
            rt = self.engine.runtimes[k]
            obj = ctx.objects[rt.plan.name]
            half = np.asarray(obj.dims, dtype=float) * 0.5
            if boxes[k].allow:
                continue
            ctx.level = k
            region, shift = rt.provider.region(ctx, _support(rt, obj.rotation, half), rt.support is not None)
            group = self.groups[k]
            others = [q for q in boxes if q.index not in group and self.engine._movable[q.index]]
            lo, hi = (region.lo, region.hi) if shift is None else (region.lo + shift, region.hi + shift)
            if near(others, lo, hi, boxes[k].reach):
                return True
        return False

    # ------------------------------------------------------------ sweeps
    def run(self, run: Attempt) -> None:
        """Apply the configured number of sweeps to the complete scene in `run`, in place."""
        if not self.movable or not self.interacting(run):
            return
        for _ in range(self.sweeps):
            for k in self.movable:
                self.update(k, run)
        run.ctx.level = len(self.engine.runtimes)

    def _boxes(self, run: Attempt) -> list[PlacedBox]:
        boxes = sorted(run.placed, key=lambda q: q.index)
        run.placed = boxes
        return boxes

    def update(self, k: int, run: Attempt) -> bool:
        """One Metropolis-within-Gibbs update of object k (and its group); True if it moved."""
        engine, ctx = self.engine, run.ctx
        runtimes = engine.runtimes
        boxes = self._boxes(run)
        group = self.groups[k]
        rt = runtimes[k]
        obj = ctx.objects[rt.plan.name]
        half = np.asarray(obj.dims, dtype=float) * 0.5
        members = [ctx.objects[runtimes[j].plan.name] for j in group]
        saved = [(o.position.copy(), o.rotation) for o in members]  # type: ignore[union-attr]
        old_measures = self._measures(group[1:], run)
        if old_measures is None:
            return False
        ctx.level = k
        try:
            region, shift = rt.provider.region(ctx, _support(rt, obj.rotation, half), rt.support is not None)
        except EmptyRegionError:
            return False
        outside = [boxes[i] for i in range(len(boxes)) if i not in group]
        run.placed, run.draws = outside, 0
        moved = engine._draw(rt, obj, half, region, shift, run)
        run.placed = boxes
        if moved and len(group) > 1 and self.redraw[k] and ctx.uniform() < REDRAW:
            moved = self._redraw(group, saved, members, run)
        elif moved:
            delta = obj.position - saved[0][0]  # type: ignore[operator]
            for o, (p, _) in zip(members[1:], saved[1:]):
                o.position = p + delta
            for j, o in zip(group[1:], members[1:]):
                runtimes[j].late_rotation(o, ctx)
            moved = self._accept(group, old_measures, run)
        if not moved:
            for o, (p, r) in zip(members, saved):
                o.position, o.rotation = p, r
        for j, o in zip(group, members):
            boxes[j] = runtimes[j].placed_box(o, np.asarray(o.dims, dtype=float) * 0.5, ctx)
        ctx.level = len(runtimes)
        return moved

    def _redraw(self, group: tuple[int, ...], saved: list, members: list, run: Attempt) -> bool:
        """Draw the dependants afresh, one by one exactly uniform on what is free, given k's new
        position; Metropolis ratio prod_j (|F_j| / |R_j|)(new) / (|F_j| / |R_j|)(old)."""
        ctx, k_rt = run.ctx, self.engine.runtimes[group[0]]
        k_half = np.asarray(members[0].dims, dtype=float) * 0.5
        outside = [q for q in run.placed if q.index not in group]
        new_k, new_rotation = members[0].position, members[0].rotation
        members[0].position, members[0].rotation = saved[0]  # the old state: the reverse proposal
        old = self._free_measures(group[1:], [*outside, k_rt.placed_box(members[0], k_half, ctx)], run, draw=False)
        members[0].position, members[0].rotation = new_k, new_rotation
        new = self._free_measures(group[1:], [*outside, k_rt.placed_box(members[0], k_half, ctx)], run, draw=True)
        if old is None or new is None or not self._accept(group, None, run):
            return False
        return new >= old or run.ctx.uniform() < new / old

    def _free_measures(self, dependants: tuple[int, ...], fixed: list[PlacedBox], run: Attempt, draw: bool) -> float | None:
        """prod_j |F_j| / |R_j| over the dependants in order, F_j the free part of j's region
        (minus every box outside the group and the group members before j); with `draw`,
        each dependant is first drawn exactly uniform on F_j. None if some F_j is empty."""
        ctx, runtimes = run.ctx, self.engine.runtimes
        fixed = list(fixed)
        factor = 1.0
        for j in dependants:
            rt = runtimes[j]
            o = ctx.objects[rt.plan.name]
            half = np.asarray(o.dims, dtype=float) * 0.5
            ctx.level = j
            try:
                region, shift = rt.provider.region(ctx, _support(rt, o.rotation, half), rt.support is not None)
                poly = region.poly if shift is None else region.poly.translate(shift)
                lo, hi = (region.lo, region.hi) if shift is None else (region.lo + shift, region.hi + shift)
                reach = rt.reach if rt.reach is not None else aabb_reach(o.rotation, half)
                free = free_space_sampler(poly, obstacles_for(near(fixed, lo, hi, reach), o.rotation, half))  # type: ignore[arg-type]
            except EmptyRegionError:
                return None
            factor *= free.measure / region.measure
            if draw:
                o.position = free.sample_one(ctx.rng)
            fixed.append(rt.placed_box(o, half, ctx))
        return factor

    def _measures(self, dependants: tuple[int, ...], run: Attempt) -> list[Prepared] | None:
        """The current regions of the dependants, or None if one is empty or excludes its object."""
        ctx, out = run.ctx, []
        for j in dependants:
            rt = self.engine.runtimes[j]
            o = ctx.objects[rt.plan.name]
            support = _support(rt, o.rotation, np.asarray(o.dims, dtype=float) * 0.5)
            ctx.level = j
            try:
                region, _ = rt.provider.region(ctx, support, rt.support is not None)
            except EmptyRegionError:
                return None
            if violated_rule(rt.provider, ctx, support, o.position) is not None:  # type: ignore[arg-type]
                return None
            out.append(region)
        return out

    def _accept(self, group: tuple[int, ...], old: list[Prepared] | None, run: Attempt) -> bool:
        """The Metropolis test of a group move: regions, collisions, requires, and for a
        translation (`old` regions given) the ratio of the dependants' region measures."""
        engine, ctx = self.engine, run.ctx
        runtimes = engine.runtimes
        new = self._measures(group[1:], run) if old is not None else []
        if new is None:
            return False
        boxes = run.placed
        moved = {}
        for j in group:
            o = ctx.objects[runtimes[j].plan.name]
            moved[j] = runtimes[j].placed_box(o, np.asarray(o.dims, dtype=float) * 0.5, ctx)
        for j, q in moved.items():
            if q.allow or j == group[0]:
                continue  # k itself was drawn free of the outside boxes; the group moved rigidly
            others = [moved.get(i, b) for i, b in enumerate(boxes) if i != j]
            box = q.box
            if first_hit(near(others, box.center, box.center, q.reach), box.center, box.rotation, box.half_extents, q.reach):
                return False
        for checks in engine._checks:
            for check in checks:
                if (check.soft is None or check.soft in ctx.active_requires) and not check.test(ctx):
                    return False
        ratio = 1.0
        for a, b in zip(old or (), new):
            if a is not b:
                ratio *= a.measure / b.measure
        return ratio >= 1.0 or ctx.uniform() < ratio
