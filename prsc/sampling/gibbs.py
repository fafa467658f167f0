"""The joint law without whole-scene rejection: Metropolis-within-Gibbs sweeps over a
sequential sample (docs/sampling.md, "The joint law").

The target is the law `--law rejection` samples: every object drawn uniform on its region
given the objects before it, conditioned on no collision and every rejection-checked
require holding, density  prod_k 1[x_k in R_k] / |R_k|  on the valid scenes.

One update re-places object k. Its dependants (the objects whose rows read it, directly or
through each other) form its group. k's new position is drawn exactly uniform on its
region minus the boxes of every object outside the group (the engine's own draw:
rejection, then the exact free-space decomposition); the outside objects do not move, so
this part is symmetric and, without dependants, an exact Gibbs draw. The dependants then
either follow (each moves by the shift of its region's bounding-box centre, as a tray
carries its cubes: accepted with min(1, prod_j |R_j(old)| / |R_j(new)|)) or, half the
time, are drawn afresh exactly on their free space (accepted with the ratio of the free
fractions |F_j| / |R_j|, new over old); either only if every dependant stays in its
region, nothing collides and every require holds.

Objects keep their own random values (sizes, pre-position rotations, colours) from the
sequential sample; only positions (and rotations that follow the position) move.
Scenes whose movable objects cannot reach one another need no update: `interacting`
detects them (once per spec for objects with bounds known in every scene, per scene for
the others), so they keep the sequential sampler's speed.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from prsc.constraints.polytope_ir import RequireCheck
from prsc.constraints.support import Support
from prsc.constraints.values import ObjectValue
from prsc.geometry.exceptions import EmptyRegionError
from prsc.sampling.attempt import Attempt
from prsc.geometry.polytope import Polytope
from prsc.sampling.collisions import PlacedBox, aabb_reach, first_hit, near, obstacles_for
from prsc.sampling.prepared import Prepared
from prsc.sampling.prepared_regions import violated_rule
from prsc.sampling.runtime import ObjectRuntime



class SweptEngine(Protocol):
    """What Gibbs sweeps read of the sequential engine (engine.py), which owns and runs them:
    an interface stated here, so that this module sits below the engine and names nothing of it."""

    runtimes: list[ObjectRuntime]
    reads: list[set[int]]  # per object: the earlier objects its rows read
    checks: list[tuple[RequireCheck, ...]]  # per object: the requires tested once it is placed
    movable: list[bool]  # per object: whether re-placing it can change anything
    index_of: dict[str, int]  # object name -> its index

    def draw_position(self, rt: ObjectRuntime, obj: ObjectValue, half: np.ndarray, region: Prepared,
                      shift: np.ndarray | None, excluded: list[Polytope], run: Attempt) -> bool: ...

# Sweeps per scene, chosen from the mixing measurement in docs/sampling.md ("How many
# sweeps"): on the cups the law reaches the exact joint value within noise after 3 sweeps.
DEFAULT_SWEEPS = 4
# A group move either lets the dependants follow k (the measure ratio decides) or, with this
# probability, draws them afresh on their free space (the ratio of free fractions decides).
# Following moves a tray with its cubes; redrawing moves cups that share a coordinate with k.
# A group whose dependants are all carried by a member (`_carried`) only follows: there the
# redraw costs two free-space decompositions per dependant and the follow is already
# accepted whenever k's new place is free (docs/sampling.md).
REDRAW = 0.5


def _half(obj: ObjectValue) -> np.ndarray:
    """The object's half extents."""
    return np.asarray(obj.dims, dtype=float) * 0.5


def _support(rt: ObjectRuntime, rotation: np.ndarray | None, half: np.ndarray) -> Support:
    """The support function the object's region was built with (as ObjectRuntime.new_value)."""
    if rt.support is not None:
        return rt.support
    if not rt.after_position and rotation is not None:
        return Support(rotation, half, "exact")
    return Support(None, half, rt.plan.orientation.bound_mode)  # type: ignore[union-attr]


class GibbsSweeps:
    """Metropolis-within-Gibbs updates of a complete scene, in place, for one engine."""

    def __init__(self, engine: SweptEngine, sweeps: int = DEFAULT_SWEEPS) -> None:
        self.engine = engine
        self.sweeps = int(sweeps)
        runtimes = engine.runtimes
        n = len(runtimes)
        readers: list[set[int]] = [set() for _ in range(n)]
        for j, reads in enumerate(engine.reads):
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
        # A group whose dependants have excluded cells (`not visible from C`) is not moved: the
        # acceptance ratios use each dependant's region measure, not that of region minus cells,
        # so such objects keep the sequential start (docs/sampling.md).
        self.movable = [k for k in range(n) if engine.movable[k]
                        and not any(engine.runtimes[j].plan.exclusions for j in self.groups[k][1:])]
        self.has_checks = any(engine.checks)
        # Fresh draws of a group need every dependant's rotation before its position.
        # The probability of a redraw move per group (a constant per spec: either kernel alone
        # keeps the joint law, so the mixture does for any fixed weights).
        self.redraw = [REDRAW if all(not runtimes[j].after_position for j in g[1:])
                       and not all(self._carried(j, g) for j in g[1:]) else 0.0 for g in self.groups]
        self._fixed_bounds()

    def _carried(self, j: int, group: tuple[int, ...]) -> bool:
        """Whether dependant j moves rigidly with a member of its group and meets nothing outside
        it on the way: it rests inside a member (a part in a bin, a cube on a tray's floor), or
        its region is a translate of one fixed region anchored to a member (a camera above a bin)."""
        rt = self.engine.runtimes[j]
        if any(m in group for m in rt.plan.rests_in):
            return True
        anchor = rt.plan.region.anchor
        return (anchor is not None and self.engine.index_of.get(anchor) in group
                and rt.support is not None and rt.provider.fixed_bounds() is not None)

    # ------------------------------------------------------------ detection
    def _fixed_bounds(self) -> None:
        """Split the movable objects once: those whose box stays within bounds known for every
        scene (static or anchored region, static size and rotation) and those only a scene can
        bound; decide once whether two of the former can reach each other."""
        runtimes = self.engine.runtimes
        centre: dict[int, tuple[np.ndarray, np.ndarray] | None] = {}
        for rt in runtimes:  # placement order: an anchor's bounds come first
            i = rt.plan.index
            if rt.plan.static_position is not None:
                centre[i] = (rt.plan.static_position, rt.plan.static_position)
                continue
            own = rt.provider.fixed_bounds() if rt.support is not None else None
            anchor = rt.plan.region.anchor
            if own is not None and rt.provider.dynamic:
                base = centre.get(self.engine.index_of[anchor]) if anchor in self.engine.index_of else None
                own = None if base is None else (own[0] + base[0], own[1] + base[1])
            centre[i] = own
        # Per movable object that can collide: its box's bounds (centre bounds, static reach) or None.
        self.bounds: dict[int, tuple[np.ndarray, np.ndarray, tuple[float, float, float]] | None] = {}
        for k in self.movable:
            rt = runtimes[k]
            if rt.allow_static is True:
                continue
            c = centre[k] if rt.allow_static is False else None
            self.bounds[k] = None if c is None or rt.reach is None else (c[0], c[1], rt.reach)
        self.per_scene = [k for k, b in self.bounds.items() if b is None]
        known = [k for k, b in self.bounds.items() if b is not None]
        self.always = False
        for k in known:
            lo, hi, reach = self.bounds[k]  # type: ignore[misc]
            for m in known:
                if m in self.groups[k] or m in runtimes[k].plan.rests_in:
                    continue
                mlo, mhi, mreach = self.bounds[m]  # type: ignore[misc]
                if np.all(lo - reach < mhi + np.asarray(mreach)) and np.all(mlo - np.asarray(mreach) < hi + reach):
                    self.always = True

    def interacting(self, run: Attempt) -> bool:
        """Whether some movable object's region reaches an object outside its group (or a
        rejection-checked require exists): otherwise the sequential sample is already exact.
        Pairs of objects with bounds known for every scene are decided once (_fixed_bounds)."""
        if self.has_checks or self.always:
            return True
        if not self.per_scene:
            return False
        ctx, boxes = run.ctx, self._boxes(run)
        runtimes = self.engine.runtimes
        scene_boxes = [boxes[m] for m in self.per_scene if not boxes[m].allow]
        for k, known in self.bounds.items():
            rt = runtimes[k]
            group, containers = self.groups[k], rt.plan.rests_in
            if known is not None:
                lo, hi, reach = known
                others = [q for q in scene_boxes if q.index not in group]
            else:
                if boxes[k].allow:
                    continue
                obj = ctx.objects[rt.plan.name]
                if rt.provider.point_rule is not None:
                    lo = hi = obj.position  # `at` a point: the region is where the object is
                else:
                    region, shift = self._region(k, run)
                    lo, hi = (region.lo, region.hi) if shift is None else (region.lo + shift, region.hi + shift)
                reach = boxes[k].reach
                others = [q for q in boxes if q.index not in group and q.index in self.bounds]
            if near(others, lo, hi, reach, containers=containers):
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
        half = _half(obj)
        members = [ctx.objects[runtimes[j].plan.name] for j in group]
        saved = [(o.position.copy(), o.rotation) for o in members]  # type: ignore[union-attr]
        redraw = len(group) > 1 and self.redraw[k] > 0 and ctx.uniform() < self.redraw[k]
        old = None if redraw else self._centres(group[1:], run)
        if not redraw and old is None:
            return False
        ctx.level = k
        support = _support(rt, obj.rotation, half)
        try:
            region, shift = rt.provider.region(ctx, support, rt.support is not None, translates=True)
        except EmptyRegionError:
            return False
        outside = [boxes[i] for i in range(len(boxes)) if i not in group]
        run.placed, run.draws = outside, 0
        moved = engine.draw_position(rt, obj, half, region, shift, rt.excluded(ctx, support), run)
        run.placed = boxes
        if moved and redraw:
            moved = self._redraw(group, saved, run)
        elif moved:
            moved = self._follow(group, [p for p, _ in saved[1:]], old, run)  # type: ignore[arg-type]
        if not moved:
            for o, (p, r) in zip(members, saved):
                o.position, o.rotation = p, r
        for j, o in zip(group, members):
            boxes[j] = runtimes[j].placed_box(o, _half(o), ctx)
        ctx.level = len(runtimes)
        return moved

    def _region(self, j: int, run: Attempt) -> tuple[Prepared, np.ndarray | None]:
        """Object j's region given the others' current positions (EmptyRegionError if empty)."""
        rt = self.engine.runtimes[j]
        o = run.ctx.objects[rt.plan.name]
        run.ctx.level = j
        return rt.provider.region(run.ctx, _support(rt, o.rotation, _half(o)), rt.support is not None, translates=True)

    def _redraw(self, group: tuple[int, ...], saved: list, run: Attempt) -> bool:
        """Draw the dependants afresh, one by one exactly uniform on what is free, given k's new
        position; Metropolis ratio prod_j (|F_j| / |R_j|)(new) / (|F_j| / |R_j|)(old)."""
        ctx, runtimes = run.ctx, self.engine.runtimes
        k = group[0]
        k_obj = ctx.objects[runtimes[k].plan.name]
        outside = [q for q in run.placed if q.index not in group]
        new_k, new_rotation = k_obj.position, k_obj.rotation
        k_obj.position, k_obj.rotation = saved[0]  # the old state: the reverse proposal
        old = self._free_measures(group[1:], [*outside, runtimes[k].placed_box(k_obj, _half(k_obj), ctx)], run, draw=False)
        k_obj.position, k_obj.rotation = new_k, new_rotation
        new = self._free_measures(group[1:], [*outside, runtimes[k].placed_box(k_obj, _half(k_obj), ctx)], run, draw=True)
        if old is None or new is None or not self._valid(group, run):
            return False
        return new >= old or ctx.uniform() < new / old

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
            half = _half(o)
            try:
                region, shift = self._region(j, run)
                lo, hi = (region.lo, region.hi) if shift is None else (region.lo + shift, region.hi + shift)
                reach = rt.reach if rt.reach is not None else aabb_reach(o.rotation, half)
                nearby = near(fixed, lo, hi, reach, containers=rt.plan.rests_in)
                if nearby:
                    free = region.free_space(shift, obstacles_for(nearby, o.rotation, half))  # type: ignore[arg-type]
            except EmptyRegionError:
                return None
            if nearby:
                factor *= free.measure / region.measure
                if draw:
                    o.position = free.sample_one(ctx.rng)
            elif draw:  # nothing can reach its region: F_j is R_j, drawn without a decomposition
                p = region.draw(ctx.rng, "exact", 0)
                o.position = p if shift is None else p + shift
            fixed.append(rt.placed_box(o, half, ctx))
        return factor

    def _centres(self, dependants: tuple[int, ...], run: Attempt) -> list[tuple[float, np.ndarray]] | None:
        """(measure, bounding-box centre) of each dependant's current region; None if one is empty."""
        out = []
        for j in dependants:
            try:
                region, shift = self._region(j, run)
            except EmptyRegionError:
                return None
            centre = (region.lo + region.hi) * 0.5
            out.append((region.measure, centre if shift is None else centre + shift))
        return out

    def _follow(self, group: tuple[int, ...], before: list[np.ndarray], old: list[tuple[float, np.ndarray]], run: Attempt) -> bool:
        """Move each dependant (in order) by the shift of its region's bounding-box centre, as a
        tray carries its cubes and cups aligned with k follow its y. The map is a translation
        given the earlier members, its own inverse for the reverse move, so it is accepted with
        min(1, prod_j |R_j(old)| / |R_j(new)|) when every dependant stays in its region and
        nothing collides."""
        ctx, runtimes = run.ctx, self.engine.runtimes
        ratio = 1.0
        for j, p, (measure, centre) in zip(group[1:], before, old):
            rt = runtimes[j]
            o = ctx.objects[rt.plan.name]
            try:
                region, shift = self._region(j, run)
            except EmptyRegionError:
                return False
            moved = (region.lo + region.hi) * 0.5
            o.position = p + (moved if shift is None else moved + shift) - centre
            rt.late_rotation(o, ctx)
            if violated_rule(rt.provider, ctx, _support(rt, o.rotation, _half(o)), o.position) is not None:
                return False
            ratio *= measure / region.measure
        return self._valid(group, run) and (ratio >= 1.0 or ctx.uniform() < ratio)

    def _valid(self, group: tuple[int, ...], run: Attempt) -> bool:
        """After a group move: no member but k collides (k was drawn free of the outside boxes)
        and every rejection-checked require holds."""
        engine, ctx = self.engine, run.ctx
        runtimes = engine.runtimes
        boxes = run.placed
        moved = {}
        for j in group:
            o = ctx.objects[runtimes[j].plan.name]
            moved[j] = runtimes[j].placed_box(o, _half(o), ctx)
        for j, q in moved.items():
            if q.allow or j == group[0]:
                continue
            others = [moved.get(i, b) for i, b in enumerate(boxes) if i != j]
            box = q.box
            rests_in = runtimes[j].plan.rests_in
            if first_hit(near(others, box.center, box.center, q.reach, containers=rests_in), box.center, box.rotation, box.half_extents, q.reach):
                return False
        for checks in engine.checks:
            for check in checks:
                if (check.soft is None or check.soft in ctx.active_requires) and not check.test(ctx):
                    return False
        return True
