"""Which objects of a packed spec Gibbs rounds draw, and how (docs/sampling.md, "Gibbs rounds"):
the plan of group_gibbs.GroupGibbs, decided once when the sampler's plan is made."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from prsc.geometry.obb import axis_aligned
from prsc.sampling.batch_values import Unbatchable
from prsc.sampling.candidate_plan import CandidateObject, CandidatePlan
from prsc.sampling.candidate_values import CandidateState
from prsc.sampling.collisions import apart
from prsc.sampling.prepared import Prepared
from prsc.sampling.runtime import ObjectRuntime

SWEEPS = 16  # sweeps per scene of fixed boxes (docs/sampling.md, "Gibbs rounds": the start correlation they leave)
# Sweeps per scene when some boxes are drawn afresh (size, yaw and centre from the exact conditional): on the
# ten-part bin the start correlation is at the noise floor after 4 (docs/sampling.md, "Gibbs rounds").
DRAWN_SWEEPS = 6


@dataclass(frozen=True, eq=False)
class GroupObject:
    """One object as the vectorised sweeps draw it."""

    name: str
    rotation: np.ndarray  # a fixed box's (the identity for a drawn one)
    half: np.ndarray  # a fixed box's half extents
    reach: np.ndarray  # half extents of its axis-aligned box (a bound over every draw for a drawn one)
    upright: bool
    aligned: bool  # its box is its axis-aligned box
    prepared: Prepared | None  # a fixed box's region (about its anchor when carried)
    anchor: str | None
    movable: bool  # redrawn in sweeps (not a point, not an anchor)
    partners: tuple[int, ...]  # objects (indices) whose boxes it may meet
    drawn: CandidateObject | None = None  # its size or yaw changes: drawn as candidate rounds draw it
    site: int = 0  # its index in the candidate plan (the counter-stream site of its centre there)
    inside: tuple[int, ...] = ()  # objects outside its group it lies apart from because its anchor's box does


def group_sweeps(objects: tuple[GroupObject, ...], asked: int) -> int:
    """The sweeps a group plan runs: DRAWN_SWEEPS when every box the sweeps move is drawn afresh (measured
    there), else SWEEPS (fixed boxes mix more slowly: ten cubes); more when asked."""
    drawn = all(o.drawn is not None for o in objects if o.movable)
    return max(DRAWN_SWEEPS if drawn else SWEEPS, asked)


def group_plan(plan: CandidatePlan, runtimes: Sequence[ObjectRuntime]) -> tuple[GroupObject, ...]:
    """The objects of a spec the vectorised sweeps draw; Unbatchable says why not."""
    if plan.requires or len(plan.soft):
        raise Unbatchable("requires checked per scene")
    anchors = {o.region.anchor for o in plan.objects if o.region.kind in ("carried", "rectangle")}
    bounds: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    items: list[tuple[str, np.ndarray, np.ndarray, np.ndarray, Prepared | None, str | None]] = []
    drawn: dict[str, CandidateObject] = {}
    for item, rt in zip(plan.objects, runtimes):
        if item.toward is not None:
            raise Unbatchable(f"{item.name} faces toward a point")
        if item.yaw is not None or any(s.constant is None for s in item.sizes):
            _drawable(item, anchors, drawn, plan)
            bounds[item.name], reach = _drawn_bounds(item, bounds[item.region.anchor])  # type: ignore[index]
            items.append((item.name, np.eye(3), np.zeros(3), reach, None, item.region.anchor))
            drawn[item.name] = item
            continue
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
    _own_draws(plan, drawn)
    index = {name: k for k, (name, *_) in enumerate(items)}
    partners = [{j for j in range(len(items)) if j != k and _may_meet(k, j, items, bounds, runtimes)} for k in range(len(items))]
    inside: dict[int, tuple[int, ...]] = {}
    for k, (name, *_rest, anchor) in enumerate(items):
        item = drawn.get(name)
        if item is not None and _contained(item, items[index[anchor]][2]):  # type: ignore[index]
            # Its boxes lie in its anchor's box, so it meets an object outside the group only where the anchor does,
            # which the anchor's own tests exclude: those tests decide for it, and it needs none of its own.
            group = {j for j, other in enumerate(items) if other[5] == anchor} | {index[anchor]}  # type: ignore[index]
            inside[k] = tuple(sorted((partners[k] & partners[index[anchor]]) - group))  # type: ignore[index]
            for j in inside[k]:
                partners[k].discard(j)
                partners[j].discard(k)
    objects = []
    for k, ((name, rotation, half, reach, prepared, anchor), rt) in enumerate(zip(items, runtimes)):
        item = drawn.get(name)
        movable = name not in anchors and (item is not None or prepared.sampler is not None)  # type: ignore[union-attr]
        objects.append(GroupObject(name, rotation, half, reach, bool(plan.objects[k].upright),
                                   item is None and axis_aligned(rotation), prepared, anchor, movable,
                                   tuple(sorted(partners[k])), item, k, inside.get(k, ())))
    for a, obj in enumerate(objects):
        group = {k for k, o in enumerate(objects) if o.anchor == obj.name}
        if obj.name in anchors and (obj.anchor is not None or obj.drawn is not None
                                    or not all(set(objects[d].partners) <= group for d in group)
                                    or not all(_standing(objects[j], j, a, anchors) for j in set(obj.partners) - group)):
            raise Unbatchable(f"{obj.name}'s group meets objects outside it, so where it stands changes its law")
    return tuple(objects)


def _contained(item: CandidateObject, anchor_half: np.ndarray) -> bool:
    """Whether every box of a drawn object lies in its anchor's box: `completely in` the anchor's floor, which
    lies within the anchor's box, and no taller than the anchor's top above that floor."""
    region = item.region
    if region.interior is None or not region.completely:
        return False
    tallest = float(item.sizes[2].hi[0])  # upright (group_plan's _drawable): its height is its extent up
    floor = region.interior.floor_top
    return bool(region.half_size[0] <= anchor_half[0] and region.half_size[1] <= anchor_half[1]
                and -anchor_half[2] <= floor and floor + tallest <= anchor_half[2])


def _standing(other: GroupObject, j: int, anchor: int, anchors: set[str | None]) -> bool:
    """Whether an object outside an anchor's group that the anchor may meet stands still where the start put it
    before the anchor: a fixed point, placed earlier, anchoring nothing (the anchor's start draw avoids it exactly)."""
    return (j < anchor and other.anchor is None and other.name not in anchors and other.prepared is not None
            and other.prepared.point is not None)


def _drawable(item: CandidateObject, anchors: set[str | None], drawn: dict[str, CandidateObject], plan: CandidatePlan) -> None:
    """Unbatchable unless an object of random size or yaw is one the sweeps draw afresh: upright on an
    upright anchor's face or floor, cut by nothing else."""
    region = item.region
    if region.kind != "rectangle" or region.cuts or region.tested is not None or not item.upright:
        raise Unbatchable(f"{item.name}'s size or rotation changes between scenes, and its region is not an "
                          "anchor's face or floor alone")
    if item.name in anchors:
        raise Unbatchable(f"{item.name}'s size or rotation changes between scenes, and another object rests on it")
    carrier = next(o for o in plan.objects if o.name == region.anchor)
    if region.anchor in drawn or carrier.yaw is not None or carrier.toward is not None or not carrier.upright:
        raise Unbatchable(f"{item.name} rests on {region.anchor}, whose rotation changes between scenes or is not upright")


def _drawn_bounds(item: CandidateObject, anchor: tuple[np.ndarray, np.ndarray]) -> tuple[tuple[np.ndarray, np.ndarray], np.ndarray]:
    """Bounds of an upright drawn box over every scene, as a centre's bounds and a reach: its footprint
    within the plan's bounds (its half diagonal, or its fixed rotation's extents), its extent in z from
    the face or floor up by its tallest height."""
    assert item.bounds is not None
    lo, hi = item.bounds[0].copy(), item.bounds[1].copy()
    top = np.array([float(s.hi[0]) for s in item.sizes]) * 0.5
    reach = np.full(3, float(np.hypot(top[0], top[1]))) if item.yaw is not None else np.abs(item.rotation) @ top
    reach[2] = top[2]
    floor = lo[2]  # the face or floor in the lowest scene (the plan's prism starts there)
    lo[2], hi[2] = floor + top[2], floor + (anchor[1][2] - anchor[0][2]) + top[2]
    return (lo, hi), reach


def _own_draws(plan: CandidatePlan, drawn: dict[str, CandidateObject]) -> None:
    """Unbatchable unless each drawn object's size and yaw read only draws of its own: the sweeps
    redraw one object at a time from its prior, which must not move another's."""
    seen: dict[int, str] = {}
    for name, item in drawn.items():
        state = CandidateState(np.arange(2, dtype=np.uint64))
        try:
            for value in (*item.sizes, *((item.yaw,) if item.yaw is not None else ())):
                value.fn(state)
        except (KeyError, TypeError):
            raise Unbatchable(f"{name}'s size or yaw reads another object's position") from None
        for draw_id in state.draws:
            if seen.setdefault(draw_id, name) != name:
                raise Unbatchable(f"{name}'s size or yaw shares a random value with {seen[draw_id]}'s")


def _may_meet(k: int, j: int, items: list, bounds: dict[str, tuple[np.ndarray, np.ndarray]],
              runtimes: Sequence[ObjectRuntime]) -> bool:
    """Whether the boxes of objects k and j may collide in some scene: neither allows it, neither rests in the
    other, and their boxes over every scene are not apart (collisions.apart)."""
    if runtimes[k].allow_static or runtimes[j].allow_static or j in runtimes[k].plan.rests_in or k in runtimes[j].plan.rests_in:
        return False
    return not apart(*bounds[items[k][0]], items[k][3], *bounds[items[j][0]], items[j][3])


