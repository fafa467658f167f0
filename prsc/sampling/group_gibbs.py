"""Gibbs sweeps vectorised over scenes, for packed specs of fixed boxes (docs/sampling.md,
"Gibbs rounds").

Where hardly a whole-scene candidate passes (ten cubes in a tray), the joint law is drawn
as the Gibbs sweeps draw it (gibbs.py): a sequential start, then sweeps that redraw each
object from its conditional given all the others. Here both run for 64 scenes at once, for
specs whose objects have a fixed size and rotation, a region that is fixed or carried by
an anchor, and no requires:
- an object's draw, given the others, is uniform on its region minus their boxes: the
  first of 512 uniform proposals that meets no box, else (rarely) the free space
  decomposed exactly for that scene, which is uniform on the free part too (the mixture
  argument of batched.BatchedSampler._free_again);
- an anchor (the tray) is not redrawn: its dependants' regions only translate with it and
  meet no box outside its group, so the joint law of the group does not depend on where
  the anchor is, and the anchor's law is its start's (uniform on its region);
- the start places objects in order, each from its region minus the earlier boxes; a dead
  end restarts the scene's start from the next stream (at most `STARTS` times).
Every draw reads the counter stream at (seed, scene, stage, object): scene k is the same in
any chunk. The law is the Gibbs sampler's: the joint law as far as `SWEEPS` sweeps mix.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from prsc.constraints.context import SceneContext
from prsc.constraints.polytope_ir import ConstraintProgram
from prsc.constraints.values import ObjectValue
from prsc.errors import PrscError
from prsc.geometry.exceptions import EmptyRegionError
from prsc.geometry.obb import CONTACT_TOL, axis_aligned
from prsc.geometry.uniform_sampling import UniformSampler
from prsc.sampling.batch_values import Unbatchable
from prsc.sampling.candidate_plan import CandidatePlan
from prsc.sampling.collisions import PlacedBox, apart, collide_pairs, obstacles_for
from prsc.sampling.counter_stream import scene_keys, uniforms
from prsc.sampling.engine import SceneResult
from prsc.sampling.prepared import Prepared
from prsc.sampling.runtime import ObjectRuntime, evaluate_params
from prsc.sampling.seeds import scene_rng
from prsc.sampling.stats import RejectionStats

SWEEPS = 16  # sweeps per scene (docs/sampling.md, "Gibbs rounds": the start correlation they leave)
PROPOSALS = (32, 480)  # uniform proposals per draw, in two blocks, before the exact free space
STARTS = 64  # starts per scene before a dead end is an error (37 % of ten cubes' starts meet one)
CHUNK = 64  # scenes drawn together
_SITE = 1 << 21  # even counter-stream sites from here: 2 * (stage * objects + k)


@dataclass(frozen=True, eq=False)
class GroupObject:
    """One object as the vectorised sweeps draw it."""

    name: str
    rotation: np.ndarray
    half: np.ndarray
    reach: np.ndarray  # half extents of its axis-aligned box
    upright: bool
    aligned: bool  # its box is its axis-aligned box
    prepared: Prepared  # its region (about its anchor when carried)
    anchor: str | None
    movable: bool  # redrawn in sweeps (not a point, not an anchor)
    partners: tuple[int, ...]  # objects (indices) whose boxes it may meet


def group_plan(plan: CandidatePlan, runtimes: Sequence[ObjectRuntime]) -> tuple[GroupObject, ...]:
    """The objects of a spec the vectorised sweeps draw; Unbatchable says why not."""
    if plan.requires or len(plan.soft):
        raise Unbatchable("requires checked per scene")
    anchors = {o.region.anchor for o in plan.objects if o.region.kind == "carried"}
    bounds: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    items: list[tuple[str, np.ndarray, np.ndarray, np.ndarray, Prepared, str | None]] = []
    for item, rt in zip(plan.objects, runtimes):
        if item.yaw is not None or item.toward is not None or any(s.constant is None for s in item.sizes):
            raise Unbatchable(f"{item.name}'s size or rotation changes between scenes")
        if item.region.kind == "fixed":
            prepared, anchor = rt.provider.static_prepared, None
        elif item.region.kind == "carried" and item.name not in anchors:
            prepared, anchor = rt.provider.anchored_prepared, item.region.anchor
        else:
            raise Unbatchable(f"{item.name}'s region is neither fixed nor carried by a fixed object")
        assert prepared is not None
        half = np.array([float(s.constant[0]) for s in item.sizes]) * 0.5
        lo, hi = (prepared.lo, prepared.hi) if anchor is None else (bounds[anchor][0] + prepared.lo, bounds[anchor][1] + prepared.hi)
        bounds[item.name] = (lo, hi)
        items.append((item.name, item.rotation, half, np.abs(item.rotation) @ half, prepared, anchor))
    objects = []
    for k, ((name, rotation, half, reach, prepared, anchor), rt) in enumerate(zip(items, runtimes)):
        partners = tuple(j for j in range(len(items)) if j != k and _may_meet(k, j, items, bounds, runtimes))
        objects.append(GroupObject(name, rotation, half, reach, bool(plan.objects[k].upright), axis_aligned(rotation), prepared, anchor,
                                   name not in anchors and prepared.sampler is not None, partners))
    for obj in objects:
        group = {k for k, o in enumerate(objects) if o.anchor == obj.name}
        if obj.name in anchors and (obj.anchor is not None or not all(set(objects[d].partners) <= group for d in group)
                                    or set(obj.partners) - group):
            raise Unbatchable(f"{obj.name}'s group meets objects outside it, so where it stands changes its law")
    return tuple(objects)


def _may_meet(k: int, j: int, items: list, bounds: dict[str, tuple[np.ndarray, np.ndarray]],
              runtimes: Sequence[ObjectRuntime]) -> bool:
    """Whether the boxes of objects k and j may collide in some scene: neither allows it, neither rests in the
    other, and their boxes over every scene are not apart (collisions.apart)."""
    if runtimes[k].allow_static or runtimes[j].allow_static or j in runtimes[k].plan.rests_in or k in runtimes[j].plan.rests_in:
        return False
    return not apart(*bounds[items[k][0]], items[k][3], *bounds[items[j][0]], items[j][3])


class GroupGibbs:
    """Draws scenes of a group plan: a start and `SWEEPS` sweeps for many scenes at once."""

    def __init__(self, objects: tuple[GroupObject, ...], cprog: ConstraintProgram, runtimes: Sequence[ObjectRuntime],
                 sweeps: int = SWEEPS) -> None:
        self.objects = objects
        self.cprog = cprog
        self.runtimes = runtimes
        self.sweeps = sweeps
        self._index = {obj.name: k for k, obj in enumerate(objects)}

    def draw(self, seed: int, indices: Sequence[int]) -> list[SceneResult]:
        """Scenes `indices` of `seed`."""
        out: list[SceneResult] = []
        for first in range(0, len(indices), CHUNK):
            out += self._chunk(seed, [int(i) for i in indices[first:first + CHUNK]])
        return out

    def _chunk(self, seed: int, indices: list[int]) -> list[SceneResult]:
        keys = scene_keys(seed, np.asarray(indices, dtype=np.uint64))
        positions = self._start(seed, indices, keys)
        for sweep in range(self.sweeps):
            for k, obj in enumerate(self.objects):
                if obj.movable:
                    positions[k] = self._redraw(k, STARTS + sweep, keys, positions, obj.partners)
        return [self._result(positions, i, seed, index) for i, index in enumerate(indices)]

    def _start(self, seed: int, indices: list[int], keys: np.ndarray) -> list[np.ndarray]:
        """Objects in order, each from its region minus the earlier boxes; a dead end starts that scene again."""
        m = len(keys)
        positions = [np.zeros((m, 3)) for _ in self.objects]
        todo = np.arange(m)
        for attempt in range(STARTS):
            stuck = np.zeros(len(todo), dtype=bool)
            sub, try_keys = [p[todo] for p in positions], keys[todo]  # the scenes this start is for
            for k, obj in enumerate(self.objects):
                earlier = tuple(j for j in obj.partners if j < k)
                if obj.prepared.point is not None:
                    placed = np.broadcast_to(obj.prepared.point, (len(todo), 3)).copy()
                    if obj.anchor is not None:
                        placed = placed + sub[self._index[obj.anchor]]
                    stuck |= self._hits(k, placed[:, None, :], sub, earlier)[:, 0]
                else:
                    placed, dead = self._draw(k, attempt, try_keys, sub, earlier)
                    stuck |= dead
                sub[k] = placed
            for k, placed in enumerate(sub):
                positions[k][todo] = placed
            todo = todo[stuck]
            if not len(todo):
                return positions
        raise PrscError(f"could not sample scene {indices[int(todo[0])]} (seed {seed}): every start of the Gibbs "
                        f"sweeps met a dead end ({STARTS} starts)")

    def _redraw(self, k: int, stage: int, keys: np.ndarray, positions: list[np.ndarray], partners: tuple[int, ...]) -> np.ndarray:
        placed, dead = self._draw(k, stage, keys, positions, partners)
        # Its own place is free, so the free space is empty only by rounding: it stays where it is.
        placed[dead] = positions[k][dead]
        return placed

    def _draw(self, k: int, stage: int, keys: np.ndarray, positions: list[np.ndarray], partners: tuple[int, ...]
              ) -> tuple[np.ndarray, np.ndarray]:
        """Object k uniform on its region minus the partners' boxes, per scene: (centres, which scenes found none)."""
        obj = self.objects[k]
        sampler = obj.prepared.sampler
        assert sampler is not None
        m, width = len(keys), sampler.dim + 1
        total = sum(PROPOSALS)
        u = uniforms(keys, _SITE + 2 * (stage * len(self.objects) + k), (total + 1) * width)
        shift = np.zeros((m, 3)) if obj.anchor is None else positions[self._index[obj.anchor]]
        out = np.zeros((m, 3))
        pending = np.arange(m)
        first = 0
        for size in PROPOSALS:  # the first free proposal by number: how they are batched changes the cost only
            block = u[pending, first * width:(first + size) * width].reshape(len(pending) * size, width)
            proposals = sampler.points(block).reshape(len(pending), size, 3) + shift[pending][:, None, :]
            free = ~self._hits(k, proposals, [p[pending] for p in positions], partners)
            found = free.any(axis=1)
            out[pending[found]] = proposals[np.flatnonzero(found), free.argmax(axis=1)[found]]
            pending = pending[~found]
            first += size
            if not len(pending):
                break
        dead = np.zeros(m, dtype=bool)
        for i in pending:
            try:
                region = self._free_space(k, shift[i] if obj.anchor is not None else None, [p[i] for p in positions], partners)
            except EmptyRegionError:
                dead[i] = True
                continue
            out[i] = region.points(u[i:i + 1, total * width:total * width + region.dim + 1])[0]
        return out, dead

    def _free_space(self, k: int, shift: np.ndarray | None, centres: list[np.ndarray], partners: tuple[int, ...]) -> UniformSampler:
        """The exact free space of object k in one scene: its region minus the partners' Minkowski obstacles."""
        obj = self.objects[k]
        boxes = [PlacedBox(self.objects[j].name, j, centres[j], self.objects[j].rotation, self.objects[j].half, False)
                 for j in partners]
        return obj.prepared.free_space(shift, obstacles_for(boxes, obj.rotation, obj.half))

    def _hits(self, k: int, centres: np.ndarray, positions: list[np.ndarray], partners: tuple[int, ...]) -> np.ndarray:
        """Which of object k's boxes at `centres` (m, s, 3: s per scene) collide with a partner's box in its
        scene (positions[j] (m, 3)): the broad phase broadcast over the scene's s boxes, which decides for
        two axis-aligned boxes; collisions.collide_pairs for the close pairs of the others."""
        obj = self.objects[k]
        hit = np.zeros(centres.shape[:2], dtype=bool)
        for j in partners:
            other = self.objects[j]
            gap = np.abs(centres - positions[j][:, None, :])
            reach = obj.reach + other.reach - CONTACT_TOL
            close = (gap[:, :, 0] < reach[0]) & (gap[:, :, 1] < reach[1]) & (gap[:, :, 2] < reach[2]) & ~hit
            if obj.aligned and other.aligned:
                hit |= close
                continue
            scenes, boxes = np.nonzero(close)
            if len(scenes):
                hit[scenes, boxes] = collide_pairs(centres[scenes, boxes], obj.rotation, obj.half, positions[j][scenes],
                                                   other.rotation, other.half, obj.reach + other.reach,
                                                   obj.upright and other.upright)
        return hit

    def _result(self, positions: list[np.ndarray], i: int, seed: int, index: int) -> SceneResult:
        """Scene i of a chunk as the sequential sampler returns it (properties from the scene's own Generator)."""
        ctx = SceneContext(scene_rng(seed, index))
        objects = []
        for obj, rt, position in zip(self.objects, self.runtimes, positions):
            plan = rt.plan
            value = ObjectValue(plan.name, plan.class_name, plan.span, np.array(position[i]), obj.rotation, rt.dims,
                                dict(plan.static_props), plan.property_fns)
            ctx.objects[plan.name] = value
            objects.append(value)
        ctx.level = len(objects)
        for rt, value in zip(self.runtimes, objects):
            rt.finish(value, ctx)
        return SceneResult(objects, evaluate_params(self.cprog, ctx), RejectionStats(scenes=1), ctx)
