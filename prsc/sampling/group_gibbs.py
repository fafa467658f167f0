"""Gibbs sweeps vectorised over scenes, for packed specs (docs/sampling.md, "Gibbs rounds").

Where hardly a whole-scene candidate passes (ten cubes in a tray, a bin of parts), the joint
law is drawn as the Gibbs sweeps draw it (gibbs.py): a sequential start, then sweeps that
redraw each object from its conditional given all the others. Here both run for 64 scenes (256
when boxes are drawn afresh) at once, for specs without requires whose objects are either
- fixed boxes (a fixed size and rotation) in a region that is fixed or carried by an anchor:
  an object's draw, given the others, is uniform on its region minus their boxes: the
  first of 512 uniform proposals that meets no box, else (rarely) the free space
  decomposed exactly for that scene, which is uniform on the free part too (the mixture
  argument of batched.BatchedSampler._free_again); or
- drawn boxes, whose size or yaw changes between scenes (a washer of random diameter at a
  random yaw), `[completely] in`/`on` an anchor's floor or face or on a fixed plane, their
  size and yaw reading no other object's draws: an update proposes the object afresh as the
  rejection reference draws it (size and yaw from their priors, the centre uniform on the
  region they leave, candidate_regions.py), and keeps the first of 512 proposals that meets
  no box. That is an exact draw of the object's whole conditional (size, yaw and centre)
  given the others; where none of the 512 is free the object stays, which is the identity
  mixed into the exact kernel with a weight that depends on the others alone, so the
  joint law is still invariant (only the mixing slows);
- an anchor (the tray) is not redrawn: its dependants' regions only translate with it and
  meet no box outside its group (or only inside the anchor's box, whose own tests decide:
  group_members._contained), so the joint law of the group does not depend on where the
  anchor is, and the anchor's law is its start's (uniform on its region minus fixed boxes);
- the start places objects in order, each from its region minus the earlier boxes; a dead
  end restarts the scene's start from the next stream (at most `STARTS` times).
Every draw reads the counter stream at (seed, scene, stage, object) (a drawn object's
proposals as candidate numbers past `_PROPOSAL_BASE`): scene k is the same in any chunk.
The law is the Gibbs sampler's: the joint law as far as `SWEEPS` sweeps mix.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from prsc.constraints.context import SceneContext
from prsc.constraints.polytope_ir import ConstraintProgram
from prsc.constraints.values import DIMENSIONS, ObjectValue
from prsc.errors import PrscError
from prsc.geometry.exceptions import EmptyRegionError
from prsc.geometry.obb import CONTACT_TOL
from prsc.geometry.uniform_sampling import UniformSampler
from prsc.sampling.candidate_values import CandidateState
from prsc.sampling.candidates import draw_box
from prsc.sampling.collisions import PlacedBox, collide_pairs, obstacles_for
from prsc.sampling.counter_stream import candidate_keys, scene_keys, uniforms
from prsc.sampling.drawn_hits import Partners, drawn_hits
from prsc.sampling.engine import SceneResult
from prsc.sampling.group_members import SWEEPS, GroupObject
from prsc.sampling.runtime import ObjectRuntime, evaluate_params
from prsc.sampling.seeds import LazySceneRng
from prsc.sampling.stats import RejectionStats

PROPOSALS = (32, 480)  # uniform proposals per draw, in two blocks, before the exact free space
DRAWN_PROPOSALS = 512  # a drawn object's proposals per update, in blocks that double from FIRST_BLOCK (a few scenes need many)
FIRST_BLOCK = 8
BLOCK_ROWS = (16, 256)  # proposals a block holds at least, over its scenes: per scene of the chunk, and at most
_DRAWN_SPAN = 512  # candidate numbers each update's proposals own (DRAWN_PROPOSALS <= it)
STARTS = 64  # starts per scene before a dead end is an error (37 % of ten cubes' starts meet one)
CHUNK = 64  # scenes drawn together (of fixed boxes)
DRAWN_CHUNK = 256  # scenes drawn together when some boxes are drawn afresh: numpy calls per update, not their size, cost most
_SITE = 1 << 21  # even counter-stream sites from here: 2 * (stage * objects + k)
_PROPOSAL_BASE = 1 << 32  # a drawn object's proposals: candidate numbers from here (candidate rounds use < 468)


@dataclass
class _Boxes:
    """The current boxes of a chunk's scenes, per object: centres (m, 3); rotations, half extents and
    reaches one array for every scene (a fixed box) or one row per scene (a drawn box), with its draws."""

    positions: list[np.ndarray]
    rotations: list[np.ndarray]
    halves: list[np.ndarray]
    reaches: list[np.ndarray]
    draws: list[dict[int, np.ndarray]]  # a drawn box's draws: draw id -> (m, 1)
    per_scene: tuple[bool, ...]

    def rows(self, rows: np.ndarray) -> "_Boxes":
        """These scenes' boxes (copies)."""
        pick = [(r[rows], h[rows], e[rows]) if own else (r, h, e)
                for r, h, e, own in zip(self.rotations, self.halves, self.reaches, self.per_scene)]
        return _Boxes([p[rows] for p in self.positions], [x[0] for x in pick], [x[1] for x in pick], [x[2] for x in pick],
                      [{d: v[rows] for d, v in draws.items()} for draws in self.draws], self.per_scene)

    def set(self, k: int, rows: np.ndarray, drawn: "_Drawn", which: np.ndarray) -> None:
        """Object k in scenes `rows` becomes the drawn rows `which`."""
        self.positions[k][rows] = drawn.positions[which]
        if self.per_scene[k]:
            self.rotations[k][rows] = drawn.rotations[which]
            self.halves[k][rows] = drawn.halves[which]
            self.reaches[k][rows] = drawn.reaches[which]
            for draw_id, values in drawn.draws.items():
                self.draws[k].setdefault(draw_id, np.zeros((len(self.positions[k]), 1)))[rows] = values[which]


@dataclass
class _Drawn:
    """Proposed boxes of one object, one row per proposal."""

    positions: np.ndarray
    rotations: np.ndarray
    halves: np.ndarray
    reaches: np.ndarray
    draws: dict[int, np.ndarray]


class GroupGibbs:
    """Draws scenes of a group plan: a start and `SWEEPS` sweeps for many scenes at once."""

    def __init__(self, objects: tuple[GroupObject, ...], cprog: ConstraintProgram, runtimes: Sequence[ObjectRuntime],
                 sweeps: int = SWEEPS) -> None:
        self.objects = objects
        self.cprog = cprog
        self.runtimes = runtimes
        self.sweeps = sweeps
        self._index = {obj.name: k for k, obj in enumerate(objects)}
        # Scenes drawn together: how many changes the cost, never a scene (each reads its own stream).
        self.chunk = DRAWN_CHUNK if any(o.drawn is not None for o in objects) else CHUNK
        self.rows = 0  # proposals drawn so far (pilot_rows)

    def draw(self, seed: int, indices: Sequence[int]) -> list[SceneResult]:
        """Scenes `indices` of `seed`."""
        return [make() for make in self.draw_lazily(seed, indices)]

    def draw_lazily(self, seed: int, indices: Sequence[int]) -> list[Callable[[], SceneResult]]:
        """Scenes `indices` of `seed`, each made when called (a drawer holds numbers, not objects for the GC to walk)."""
        out: list[Callable[[], SceneResult]] = []
        for first in range(0, len(indices), self.chunk):
            chunk = [int(i) for i in indices[first:first + self.chunk]]
            out += self._results(self._sweep(seed, chunk), seed, chunk)
        return out

    def pilot_rows(self, seed: int, indices: Sequence[int]) -> int:
        """Proposals scenes `indices` of `seed` draw, start and sweeps (sampler_plan's cost of Gibbs rounds)."""
        self.rows = 0
        self._sweep(seed, [int(i) for i in indices])
        return self.rows

    def _sweep(self, seed: int, indices: list[int]) -> _Boxes:
        """The chunk's boxes after its start and sweeps."""
        keys = scene_keys(seed, np.asarray(indices, dtype=np.uint64))
        boxes = self._start(seed, indices, keys)
        every = np.arange(len(keys))
        stack = self._partner_boxes(boxes, tuple(range(len(self.objects))))  # every box, kept as each one moves
        for sweep in range(self.sweeps):
            for k, obj in enumerate(self.objects):
                if not obj.movable:
                    continue
                if obj.drawn is not None:
                    drawn, found = self._propose(k, STARTS + sweep, keys, boxes, obj.partners, stack.columns(obj.partners))
                    boxes.set(k, every[found], drawn, np.flatnonzero(found))  # where none is free it stays
                    stack.refresh(k, boxes.positions[k], (boxes.rotations[k], boxes.halves[k], boxes.reaches[k]))
                else:
                    boxes.positions[k] = self._redraw(k, STARTS + sweep, keys, boxes, obj.partners)
                    stack.refresh(k, boxes.positions[k], None)
        return boxes

    def _boxes(self, m: int) -> _Boxes:
        """A chunk's boxes before the start: fixed boxes as they are, drawn ones empty."""
        per_scene = tuple(o.drawn is not None for o in self.objects)
        def each(fixed: list[np.ndarray], shape: tuple[int, ...]) -> list[np.ndarray]:
            return [np.zeros((m,) + shape) if own else a for a, own in zip(fixed, per_scene)]
        return _Boxes([np.zeros((m, 3)) for _ in self.objects], each([o.rotation for o in self.objects], (3, 3)),
                      each([o.half for o in self.objects], (3,)), each([o.reach for o in self.objects], (3,)),
                      [{} for _ in self.objects], per_scene)

    def _start(self, seed: int, indices: list[int], keys: np.ndarray) -> _Boxes:
        """Objects in order, each from its region minus the earlier boxes; a dead end starts that scene again."""
        m = len(keys)
        boxes = self._boxes(m)
        todo = np.arange(m)
        for attempt in range(STARTS):
            stuck = np.zeros(len(todo), dtype=bool)
            sub, try_keys = boxes.rows(todo), keys[todo]  # the scenes this start is for
            every = np.arange(len(todo))
            for k, obj in enumerate(self.objects):
                earlier = tuple(j for j in obj.partners if j < k)
                if obj.drawn is not None:
                    drawn, found = self._propose(k, attempt, try_keys, sub, earlier)
                    stuck |= ~found
                    sub.set(k, every[found], drawn, np.flatnonzero(found))
                    continue
                if obj.prepared is not None and obj.prepared.point is not None:
                    placed = np.broadcast_to(obj.prepared.point, (len(todo), 3)).copy()
                    if obj.anchor is not None:
                        placed = placed + sub.positions[self._index[obj.anchor]]
                    stuck |= self._hits(k, placed[:, None, :], None, sub, earlier)[:, 0]
                else:
                    placed, dead = self._draw(k, attempt, try_keys, sub, earlier)
                    stuck |= dead
                sub.positions[k] = placed
            done = ~stuck
            rows = todo[done]
            for k in range(len(self.objects)):
                boxes.positions[k][rows] = sub.positions[k][done]
                if boxes.per_scene[k]:
                    boxes.rotations[k][rows], boxes.halves[k][rows] = sub.rotations[k][done], sub.halves[k][done]
                    boxes.reaches[k][rows] = sub.reaches[k][done]
                    for draw_id, values in sub.draws[k].items():
                        boxes.draws[k].setdefault(draw_id, np.zeros((m, 1)))[rows] = values[done]
            todo = todo[stuck]
            if not len(todo):
                return boxes
        raise PrscError(f"could not sample scene {indices[int(todo[0])]} (seed {seed}): every start of the Gibbs "
                        f"sweeps met a dead end ({STARTS} starts)")

    def _redraw(self, k: int, stage: int, keys: np.ndarray, boxes: _Boxes, partners: tuple[int, ...]) -> np.ndarray:
        placed, dead = self._draw(k, stage, keys, boxes, partners)
        # Its own place is free, so the free space is empty only by rounding: it stays where it is.
        placed[dead] = boxes.positions[k][dead]
        return placed

    def _draw(self, k: int, stage: int, keys: np.ndarray, boxes: _Boxes, partners: tuple[int, ...]
              ) -> tuple[np.ndarray, np.ndarray]:
        """Fixed box k uniform on its region minus the partners' boxes, per scene: (centres, which scenes found none)."""
        obj = self.objects[k]
        assert obj.prepared is not None
        sampler = obj.prepared.sampler
        assert sampler is not None
        positions = boxes.positions
        m, width = len(keys), sampler.dim + 1
        total = sum(PROPOSALS)
        u = uniforms(keys, _SITE + 2 * (stage * len(self.objects) + k), (total + 1) * width)
        shift = np.zeros((m, 3)) if obj.anchor is None else positions[self._index[obj.anchor]]
        out = np.zeros((m, 3))
        pending = np.arange(m)
        first = 0
        for size in PROPOSALS:  # the first free proposal by number: how they are batched changes the cost only
            block = u[pending, first * width:(first + size) * width].reshape(len(pending) * size, width)
            self.rows += len(block)
            proposals = sampler.points(block).reshape(len(pending), size, 3) + shift[pending][:, None, :]
            free = ~self._hits(k, proposals, None, boxes.rows(pending), partners)
            found = free.any(axis=1)
            out[pending[found]] = proposals[np.flatnonzero(found), free.argmax(axis=1)[found]]
            pending = pending[~found]
            first += size
            if not len(pending):
                break
        dead = np.zeros(m, dtype=bool)
        for i in pending:
            try:
                region = self._free_space(k, shift[i] if obj.anchor is not None else None, boxes, int(i), partners)
            except EmptyRegionError:
                dead[i] = True
                continue
            out[i] = region.points(u[i:i + 1, total * width:total * width + region.dim + 1])[0]
        return out, dead

    def _propose(self, k: int, stage: int, keys: np.ndarray, boxes: _Boxes, partners: tuple[int, ...],
                 partner_boxes: Partners | None = None) -> tuple[_Drawn, np.ndarray]:
        """Drawn box k proposed afresh (size, yaw, centre) as the rejection reference draws it, per scene the
        first proposal that meets no partner's box: (the kept proposals, one row per scene; which scenes found one)."""
        obj = self.objects[k]
        item = obj.drawn
        assert item is not None
        m = len(keys)
        kept = _Drawn(np.zeros((m, 3)), np.zeros((m, 3, 3)), np.zeros((m, 3)), np.zeros((m, 3)), {})
        found = np.zeros(m, dtype=bool)
        pending = np.arange(m)
        first = _PROPOSAL_BASE + (stage * len(self.objects) + k) * _DRAWN_SPAN
        last = first + DRAWN_PROPOSALS
        partners_of_all = self._partner_boxes(boxes, partners) if partner_boxes is None else partner_boxes
        upright = obj.upright and all(self.objects[j].upright for j in partners)
        size = FIRST_BLOCK
        least = min(BLOCK_ROWS[0] * m, BLOCK_ROWS[1])
        while first < last:  # the first free proposal by number: how they are batched changes the cost only
            # Blocks double, and hold at least `least` proposals: where few scenes are left, numpy calls cost most.
            size = min(max(size, -(-least // len(pending))), last - first)
            state = CandidateState(candidate_keys(keys[pending], first, size))
            n = len(state.keys)
            self.rows += n
            anchor = item.region.anchor
            if anchor is not None:  # the anchor is a fixed box: its rotation and size are the same in every scene
                a = self._index[anchor]
                state.positions[anchor] = np.repeat(boxes.positions[a][pending], size, axis=0)
                state.rotations[anchor] = np.broadcast_to(boxes.rotations[a], (n, 3, 3))
                state.dims[anchor] = np.broadcast_to(2.0 * boxes.halves[a], (n, 3))
            valid = draw_box(item, obj.site, state)
            rotations, halves = state.rotations[item.name], state.dims[item.name] * 0.5
            reaches = np.einsum("nij,nj->ni", np.abs(rotations), halves)
            shape = (len(pending), size)
            centres = state.positions[item.name]
            others = partners_of_all if len(pending) == m else partners_of_all.rows(pending)
            free = valid.reshape(shape) & ~drawn_hits(
                centres.reshape(shape + (3,)), rotations.reshape(shape + (3, 3)), halves.reshape(shape + (3,)),
                reaches.reshape(shape + (3,)), valid.reshape(shape), others, upright)
            hit = free.any(axis=1)
            rows = np.flatnonzero(hit) * size + free.argmax(axis=1)[hit]
            scenes = pending[hit]
            kept.positions[scenes], kept.rotations[scenes], kept.halves[scenes] = centres[rows], rotations[rows], halves[rows]
            kept.reaches[scenes] = reaches[rows]
            for draw_id, values in state.draws.items():
                kept.draws.setdefault(draw_id, np.zeros((m, 1)))[scenes] = values[rows] if len(values) > 1 else values[0]
            found[scenes] = True
            pending = pending[~hit]
            first += size
            size *= 2
            if not len(pending):
                break
        return kept, found

    def _partner_boxes(self, boxes: _Boxes, partners: tuple[int, ...]) -> Partners:
        """The partners' boxes of every scene, stacked (drawn_hits.Partners)."""
        m = len(boxes.positions[0])
        if not partners:
            return Partners.of(np.zeros((m, 0, 3)), np.zeros((m, 0, 3)), np.zeros((m, 0, 3)), np.zeros((m, 0, 3, 3)))

        def stack(arrays: list[np.ndarray], shape: tuple[int, ...]) -> np.ndarray:
            return np.stack([a if boxes.per_scene[j] else np.broadcast_to(a, (m,) + shape) for j, a in zip(partners, arrays)],
                            axis=1)

        return Partners.of(np.stack([boxes.positions[j] for j in partners], axis=1), stack([boxes.reaches[j] for j in partners], (3,)),
                           stack([boxes.halves[j] for j in partners], (3,)), stack([boxes.rotations[j] for j in partners], (3, 3)))

    def _free_space(self, k: int, shift: np.ndarray | None, boxes: _Boxes, i: int, partners: tuple[int, ...]) -> UniformSampler:
        """The exact free space of fixed box k in scene i: its region minus the partners' Minkowski obstacles."""
        obj = self.objects[k]
        assert obj.prepared is not None
        placed = []
        for j in partners:
            rotation, half = boxes.rotations[j], boxes.halves[j]
            if boxes.per_scene[j]:
                rotation, half = rotation[i], half[i]
            placed.append(PlacedBox(self.objects[j].name, j, boxes.positions[j][i], rotation, half, False))
        return obj.prepared.free_space(shift, obstacles_for(placed, obj.rotation, obj.half))

    def _hits(self, k: int, centres: np.ndarray, own: tuple[np.ndarray, np.ndarray, np.ndarray] | None, boxes: _Boxes,
              partners: tuple[int, ...], live: np.ndarray | None = None) -> np.ndarray:
        """Which of object k's boxes at `centres` (m, s, 3: s per scene) collide with a partner's box in its
        scene: the broad phase broadcast over the scene's s boxes, which decides for two axis-aligned boxes;
        collisions.collide_pairs for the close pairs of the others. `own`: a drawn box's rotations, half
        extents and reaches per proposal (m, s, ...), else k's fixed box; `live`: the proposals worth testing."""
        obj = self.objects[k]
        hit = np.zeros(centres.shape[:2], dtype=bool) if live is None else ~live
        rotation, half, reach = (obj.rotation, obj.half, obj.reach) if own is None else own
        for j in partners:
            other = self.objects[j]
            position = boxes.positions[j]
            gap = np.abs(centres - position[:, None, :])
            other_reach = boxes.reaches[j][:, None, :] if boxes.per_scene[j] else boxes.reaches[j]
            span = reach + other_reach - CONTACT_TOL
            if span.ndim == 1:
                close = (gap[:, :, 0] < span[0]) & (gap[:, :, 1] < span[1]) & (gap[:, :, 2] < span[2]) & ~hit
            else:
                close = np.all(gap < span, axis=2) & ~hit
            if own is None and obj.aligned and other.aligned:
                hit |= close
                continue
            scenes, boxes_at = np.nonzero(close)
            if not len(scenes):
                continue
            if own is None and not boxes.per_scene[j]:  # two fixed boxes, as before drawn boxes joined
                hit[scenes, boxes_at] = collide_pairs(centres[scenes, boxes_at], obj.rotation, obj.half, position[scenes],
                                                      other.rotation, other.half, obj.reach + other.reach,
                                                      obj.upright and other.upright)
                continue
            mine = (rotation, half, reach) if own is None else (rotation[scenes, boxes_at], half[scenes, boxes_at],
                                                                 reach[scenes, boxes_at])
            theirs = (boxes.rotations[j], boxes.halves[j], boxes.reaches[j])
            if boxes.per_scene[j]:
                theirs = tuple(a[scenes] for a in theirs)
            hit[scenes, boxes_at] = collide_pairs(centres[scenes, boxes_at], mine[0], mine[1], position[scenes],
                                                  theirs[0], theirs[1], mine[2] + theirs[2], obj.upright and other.upright)
        return hit if live is None else hit & live

    def _results(self, boxes: _Boxes, seed: int, indices: list[int]) -> list[Callable[[], SceneResult]]:
        """What makes each of the chunk's scenes as the sequential sampler returns it: its numbers as lists."""
        positions = [p.tolist() for p in boxes.positions]
        dims = [(2.0 * h).tolist() if own else None for h, own in zip(boxes.halves, boxes.per_scene)]
        draws = [[(draw_id, values[:, 0].tolist()) for draw_id, values in d.items()] for d in boxes.draws]
        return [functools.partial(self._result, boxes.rotations, positions, dims, draws, seed, index, i)
                for i, index in enumerate(indices)]

    def _result(self, rotations: list[np.ndarray], positions: list[list], dims: list[list | None], draws: list[list],
                seed: int, index: int, i: int) -> SceneResult:
        """Scene i of a chunk (properties from its own Generator, a drawn box's size and yaw from the draws it kept)."""
        ctx = SceneContext(LazySceneRng(seed, index))  # type: ignore[arg-type]
        objects = []
        for k, (obj, rt) in enumerate(zip(self.objects, self.runtimes)):
            plan = rt.plan
            props = dict(plan.static_props)
            if obj.drawn is None:
                rotation, size = obj.rotation, rt.dims
            else:
                rotation, size = rotations[k][i].copy(), tuple(dims[k][i])  # type: ignore[index]
                props.update(zip(DIMENSIONS, size))
                for draw_id, values in draws[k]:
                    ctx.draws[draw_id] = values[i]
            value = ObjectValue(plan.name, plan.class_name, plan.span, np.array(positions[k][i]), rotation, size,
                                props, plan.property_fns)
            ctx.objects[plan.name] = value
            objects.append(value)
        ctx.level = len(objects)
        for rt, value in zip(self.runtimes, objects):
            rt.finish(value, ctx)
        return SceneResult(objects, evaluate_params(self.cprog, ctx), RejectionStats(scenes=1), ctx)
