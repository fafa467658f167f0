"""Batched sampling: many scenes of one spec at once, numpy vectorised over scenes
(docs/sampling.md, "Batched sampling").

A spec is batched when its plan (`batch_plan`) proves, before any scene is drawn, that
placing its objects one by one never meets a collision candidate, a require, an excluded
cell or a region that changes shape:
- each object has a fixed size, rotation and property set (its JSON is a template);
- its region is the same in every scene (drawn uniformly, or one point), or the same
  region carried by one earlier object (`on tr_1`) that the static rows provably never
  cut, or an `at V` point with V vectorisable and provably inside the static rows;
- the boxes that two objects could occupy in any scene are apart (or one rests in the
  other), as the sequential sampler's broad phase would find them in every scene.
Then each object's conditional law is uniform on a region of the same measure in every
scene, so the sequential law is the joint one (docs/sampling.md, "The law of a scene") and
the sampler draws it without Gibbs sweeps or rejection. Every draw comes from the
counter stream (counter_stream.py) at (seed, index, site): scene k is the same whether it
is drawn alone or in a batch of any size.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Sequence

import numpy as np

from prsc.constraints.context import SceneContext
from prsc.constraints.polytope_ir import ConstraintProgram
from prsc.constraints.values import ObjectValue
from prsc.errors import PrscError
from prsc.geometry.exceptions import EmptyRegionError, UnboundedRegionError
from prsc.geometry.polytope import Polytope
from prsc.geometry.uniform_sampling import UniformSampler
from prsc.ir import model as ir
from prsc.sampling.batch_values import BatchCompiler, BatchState, BatchValue, Unbatchable
from prsc.geometry.obb import collides_many
from prsc.sampling.collisions import CONTACT_TOL, PlacedBox, apart, near, obstacles_for
from prsc.sampling.counter_stream import scene_keys, uniforms
from prsc.sampling.prepared import TOL, Prepared
from prsc.sampling.runtime import ObjectRuntime

_LIMIT = 1 << 64  # seeds and scene indices are unsigned 64-bit counters of the stream


@dataclass(frozen=True, eq=False)
class BatchObject:
    """How one object's centre is drawn in a batch, and where it can be in any scene."""

    name: str
    rotation: np.ndarray
    half: np.ndarray
    reach: tuple[float, float, float]  # half extents of its axis-aligned box
    corners: np.ndarray  # (m, 3): points whose convex hull holds its centre in every scene
    fixed: np.ndarray | None = None  # the same centre in every scene
    region: UniformSampler | None = None  # drawn uniformly from it (plus the anchor's centre when anchored)
    anchor: str | None = None
    point: BatchValue | None = None  # `at V`
    prepared: Prepared | None = None  # a carried region prepared about its anchor: each scene's own free space
    avoids: frozenset[str] = frozenset()  # fixed objects whose boxes `region` already leaves out
    # Fixed boxes an anchored object may meet in some scenes: tested per scene, and a scene whose
    # draw hits one draws again from its own free space (the sequential sampler's law, below).
    checks: tuple[PlacedBox, ...] = ()

    @property
    def lo(self) -> np.ndarray:
        """Lower corner of its centre's bounds over every scene."""
        return self.corners.min(axis=0)

    @property
    def hi(self) -> np.ndarray:
        """Upper corner of its centre's bounds over every scene."""
        return self.corners.max(axis=0)


@dataclass(frozen=True, eq=False)
class BatchPlan:
    """A spec's objects as the batched sampler draws them, and its parameters."""

    objects: tuple[BatchObject, ...]
    params: tuple[tuple[str, Any], ...]  # name -> a constant JSON value or a BatchValue

    @property
    def fixed_params(self) -> bool:
        """Whether every parameter has the same value in every scene."""
        return not any(isinstance(value, BatchValue) for _, value in self.params)


def batch_plan(cprog: ConstraintProgram, runtimes: Sequence[ObjectRuntime]) -> BatchPlan:
    """The batch plan of a lowered spec (a ConstraintProgram and its runtimes); Unbatchable says why not."""
    if cprog.soft_requires or cprog.scene_checks:
        raise Unbatchable("requires checked per scene")
    known: dict[str, tuple[np.ndarray, np.ndarray, tuple[float, float, float]]] = {}
    compiler = BatchCompiler(cprog.program, known)
    objects: list[BatchObject] = []
    for rt in runtimes:
        item = _separated(_batch_object(rt, compiler, objects, runtimes), objects, rt, runtimes)
        objects.append(item)
        known[item.name] = (item.lo, item.hi, rt.dims)  # type: ignore[assignment]
    params: list[tuple[str, Any]] = []
    for param in cprog.program.params:
        value = param.value
        params.append((param.name, value.value if isinstance(value, ir.Const) else compiler.compile(value)))
    return BatchPlan(tuple(objects), tuple(params))


def _batch_object(rt: ObjectRuntime, compiler: BatchCompiler, placed: list[BatchObject],
                  runtimes: Sequence[ObjectRuntime]) -> BatchObject:
    plan = rt.plan
    name = plan.name
    if rt.half is None or rt.rotation is None or rt.after_position or rt.reach is None or rt.support is None:
        raise Unbatchable(f"{name}'s size or rotation changes between scenes")
    if rt.allow_static is None or set(plan.property_fns) - set(plan.static_props):
        raise Unbatchable(f"{name}'s properties change between scenes")
    if plan.checks or plan.exclusions:
        raise Unbatchable(f"{name} has requires or excluded cells checked per scene")
    if any(rule.soft is not None for rule in plan.rules):
        raise Unbatchable(f"{name} has a soft require")
    shape = (rt.rotation, rt.half, rt.reach)
    provider = rt.provider
    mode = provider.mode
    if mode == "anchored":
        return _anchored(rt, {o.name: o for o in placed})
    if mode != "static":
        return _point(rt, compiler)
    try:
        prepared = provider.static_prepared if provider.fixed_bounds() is not None else None
        if prepared is None:  # the sequential sampler explains an empty or unbounded region
            raise Unbatchable(f"{name}'s region is empty or unbounded")
        fixed = [_box(o, runtimes[i]) for i, o in enumerate(placed) if o.fixed is not None]
        near_fixed = [] if rt.allow_static else near(fixed, prepared.lo, prepared.hi, rt.reach, containers=plan.rests_in)
        if prepared.point is not None:
            if near_fixed:
                raise Unbatchable(f"{name}'s fixed place is checked against {near_fixed[0].name} per scene")
            return BatchObject(name, *shape, prepared.point[None, :], fixed=prepared.point.copy())
        assert prepared.sampler is not None
        if not near_fixed:
            return BatchObject(name, *shape, _corners(prepared.sampler), region=prepared.sampler)
        # The sequential sampler's static free space (engine.SequentialSampler._static_free_space):
        # the region minus the fixed boxes it could meet, decomposed once.
        free = prepared.free_space(None, obstacles_for(near_fixed, rt.rotation, rt.half))
        return BatchObject(name, *shape, _corners(free), region=free, avoids=frozenset(q.name for q in near_fixed))
    except EmptyRegionError:
        raise Unbatchable(f"{name} has no free place") from None
    except UnboundedRegionError:
        raise Unbatchable(f"{name}'s region is unbounded") from None


def _box(item: BatchObject, rt: ObjectRuntime) -> PlacedBox:
    """A fixed object's box as the sequential sampler places it."""
    assert item.fixed is not None
    return PlacedBox(item.name, rt.plan.index, item.fixed, item.rotation, item.half, bool(rt.allow_static))


def _point(rt: ObjectRuntime, compiler: BatchCompiler) -> BatchObject:
    """An object `at V`: V vectorised, provably inside the object's other (static) rows."""
    provider, name = rt.provider, rt.plan.name
    point_rule = provider.point_rule
    if point_rule is None or provider.dynamic != (point_rule,):
        raise Unbatchable(f"{name}'s region changes shape between scenes")
    point = compiler.compile(point_rule.args[0])
    if not point.vector:
        raise Unbatchable(f"{name}'s `at` is not a vector")
    box = _box_corners(point.lo, point.hi)
    static = provider.static_rows
    if static is not None and (len(static.d) or not rows_hold(static, box)):
        raise Unbatchable(f"{name}'s `at` point may leave its other rows")
    return BatchObject(name, rt.rotation, rt.half, rt.reach, box, point=point)  # type: ignore[arg-type]


def _anchored(rt: ObjectRuntime, placed: dict[str, BatchObject]) -> BatchObject:
    """An object carried by an earlier one: the anchored region, which the static rows never cut."""
    provider, name = rt.provider, rt.plan.name
    anchor = rt.plan.region.anchor
    provider.fixed_bounds()  # prepares the anchored region and decides whether the static rows may cut it
    prepared = provider.anchored_prepared
    if prepared is None or anchor not in placed:
        raise Unbatchable(f"{name}'s region carried by {anchor} is cut by its static rows")
    if prepared.sampler is None:
        raise Unbatchable(f"{name}'s region carried by {anchor} is a point")
    carried = carried_corners(prepared.sampler, placed[anchor].corners, provider.static_rows)
    if carried is None:
        raise Unbatchable(f"{name}'s region carried by {anchor} may be cut by its static rows")
    return BatchObject(name, rt.rotation, rt.half, rt.reach, carried, region=prepared.sampler,  # type: ignore[arg-type]
                       anchor=anchor, prepared=prepared)


def carried_corners(region: UniformSampler, anchors: np.ndarray, static: Polytope | None) -> np.ndarray | None:
    """Points whose hull holds a region carried by an anchor whose centre lies in the hull of `anchors`,
    or None when the static rows may cut it somewhere there."""
    carried = (anchors[:, None, :] + _corners(region)[None, :, :]).reshape(-1, 3)
    # With twice the sequential sampler's margin (regions.RegionProvider._anchored_region): its
    # test on one scene's rounded numbers then passes too.
    if static is not None and not rows_hold(static, carried, margin=2 * TOL):
        return None
    return carried


def _separated(item: BatchObject, placed: list[BatchObject], rt: ObjectRuntime,
               runtimes: Sequence[ObjectRuntime]) -> BatchObject:
    """The object, with the fixed boxes it must be tested against per scene; Unbatchable when an
    earlier box could be a collision candidate in some scene (collisions.near's test on the
    bounds of every scene) and no per-scene test covers it."""
    if rt.allow_static:
        return item
    checks = []
    for j, other in enumerate(placed):
        if runtimes[j].allow_static or j in rt.plan.rests_in or other.name in item.avoids:
            continue
        if apart(other.lo, other.hi, other.reach, item.lo, item.hi, item.reach):
            continue
        if other.fixed is None or item.anchor is None:
            raise Unbatchable(f"{item.name} and {other.name} may touch")
        checks.append(_box(other, runtimes[j]))
    return replace(item, checks=tuple(checks)) if checks else item


def _corners(sampler: UniformSampler) -> np.ndarray:
    return np.unique(sampler.vertices(), axis=0)


def _box_corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    return np.array([[(lo, hi)[i >> k & 1][k] for k in range(3)] for i in range(8)], dtype=float)


def rows_hold(rows: Polytope, points: np.ndarray, margin: float = 0.0) -> bool:
    """Whether every point meets every inequality row (with `margin` metres to spare, scaled as the sampler's)."""
    if not len(rows.b):
        return True
    norms = np.maximum(np.linalg.norm(rows.A, axis=1), 1.0)
    return bool(np.all(rows.A @ points.T <= (rows.b - margin * norms)[:, None]))


class BatchedSampler:
    """Draws the centres of a batch plan's objects for many scene indices at once."""

    def __init__(self, plan: BatchPlan) -> None:
        self.plan = plan

    def draw(self, seed: int, indices: Sequence[int] | np.ndarray) -> BatchState:
        """The batch's state: every object's centre (n, 3) and every draw, for scenes `indices` of `seed`."""
        keys = scene_keys(_counter(seed, "seed"), _indices(indices))
        state = BatchState(keys)
        n = len(keys)
        for k, item in enumerate(self.plan.objects):
            if item.fixed is not None:
                centre = np.broadcast_to(item.fixed, (n, 3))
            elif item.point is not None:
                centre = np.broadcast_to(item.point.fn(state), (n, 3))
            else:
                assert item.region is not None
                centre = item.region.points(uniforms(keys, 4 * k, item.region.dim + 1))
                if item.anchor is not None:
                    centre = centre + state.positions[item.anchor]
                if item.checks:
                    self._free_again(k, item, centre, state, seed, indices)
            state.positions[item.name] = centre
        return state

    def _free_again(self, k: int, item: BatchObject, centre: np.ndarray, state: BatchState, seed: int,
                    indices: Sequence[int] | np.ndarray) -> None:
        """Scenes whose draw of `item` hits a fixed box draw it again from that scene's free space (in place).

        A first draw uniform on the region R, kept when it falls in the free part F, else a
        draw uniform on F, is uniform on F: P(A) = |A∩F|/|R| + (1 - |F|/|R|) |A∩F|/|F| = |A∩F|/|F|.
        The sequential sampler's rejection then decomposition gives the same law."""
        hit = np.zeros(len(centre), dtype=bool)
        reach = np.array(item.reach)
        for box in item.checks:
            # collisions.near's broad phase per scene, then the exact test where it cannot tell.
            c, e = np.array(box.center), np.array(box.reach)
            close = np.flatnonzero(np.all((c + e - CONTACT_TOL > centre - reach) & (c - e + CONTACT_TOL < centre + reach), axis=1))
            if len(close):
                m = len(close)
                hit[close] |= collides_many(box.box, centre[close], np.broadcast_to(item.rotation, (m, 3, 3)),
                                            np.broadcast_to(item.half, (m, 3)))
        assert item.anchor is not None and item.prepared is not None
        obstacles = obstacles_for(list(item.checks), item.rotation, item.half) if hit.any() else []
        for i in np.flatnonzero(hit):
            try:
                free = item.prepared.free_space(state.positions[item.anchor][i], obstacles)
            except EmptyRegionError:
                raise PrscError(f"could not sample scene {int(indices[i])} (seed {seed}): {item.name} has no free place "
                                f"on {item.anchor} there") from None
            centre[i] = free.points(uniforms(state.keys[i:i + 1], 4 * k + 2, free.dim + 1))[0]

    def params(self, state: BatchState) -> list[dict[str, Any]]:
        """Each scene's parameter values (plain JSON data), every parameter evaluated once for the batch."""
        columns: list[tuple[str, Any, bool]] = []  # (name, value or per-scene rows, whether per scene)
        for name, value in self.plan.params:
            if isinstance(value, BatchValue):
                rows = np.broadcast_to(value.fn(state), (len(state.keys), 3 if value.vector else 1)).tolist()
                columns.append((name, rows if value.vector else [row[0] for row in rows], True))
            else:
                columns.append((name, float(value) if isinstance(value, int) and not isinstance(value, bool) else value, False))
        return [{name: value[i] if per_scene else value for name, value, per_scene in columns} for i in range(len(state.keys))]

    def objects(self, state: BatchState, i: int, runtimes: Sequence[ObjectRuntime]) -> tuple[list[ObjectValue], SceneContext]:
        """Scene i of a batch as the sequential sampler returns it: object values and a context holding its draws."""
        ctx = SceneContext(None)  # type: ignore[arg-type]  # every draw is memoised below: nothing reads a stream
        for draw_id, values in state.draws.items():
            ctx.draws[draw_id] = float(values[i if len(values) > 1 else 0, 0])
        out = []
        for rt in runtimes:
            plan = rt.plan
            position = np.array(state.positions[plan.name][i])
            obj = ObjectValue(plan.name, plan.class_name, plan.span, position, rt.rotation, rt.dims,
                              dict(plan.static_props), plan.property_fns)
            ctx.objects[plan.name] = obj
            out.append(obj)
        return out, ctx


def _counter(value: Any, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 0 <= value < _LIMIT:
        raise PrscError(f"the {what} must be an integer in [0, 2^64), got {value!r}")
    return int(value)


def _indices(indices: Sequence[int] | np.ndarray) -> np.ndarray:
    """The scene indices as the stream's counters (each checked: a non-negative 64-bit integer)."""
    if isinstance(indices, range):
        for index in (indices[0], indices[-1]) if len(indices) else ():
            _counter(index, "scene index")
    elif isinstance(indices, np.ndarray) and indices.dtype.kind in "iu":
        if len(indices) and indices.min() < 0:
            raise PrscError(f"the scene index must be an integer in [0, 2^64), got {int(indices.min())}")
    else:
        for index in indices:
            _counter(index, "scene index")
    return np.asarray(indices, dtype=np.uint64)
