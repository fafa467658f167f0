"""The joint law by whole-scene rejection, vectorised over candidate scenes
(docs/sampling.md, "Candidate rounds").

The rejection reference (`--law rejection`: engine.py's joint mode) draws every object
uniformly on its whole region given the objects before it, ignoring collisions and
rejection-checked requires, and keeps the scene when none collides and every require
holds; its law is the spec's joint law. Here each scene draws its candidates in rounds, all
in numpy at once: every object's size, yaw and centre, then every test, over arrays with
one row per candidate (candidate_plan.py decides how, once per spec). A scene keeps its first
candidate that passes, in candidate order. Candidate c of scene k under seed s reads the
counter stream at (s, k, c) alone, so a scene is the same whatever other scenes share its
batch, whatever -n, --jobs or Ray.

When none of a scene's first `BUDGET` candidates passes (a packed spec, such as ten cubes in a
tray), the scene is drawn by the Gibbs sampler instead, from its own Generator. Either
way the scene follows the joint law: the first passing candidate is a draw of it, and
whether any passes depends on the scene's stream alone, so the mixture of the two is the
joint law too (as far as the Gibbs sweeps have mixed: docs/sampling.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence, Union

import numpy as np

from prsc.constraints.context import SceneContext
from prsc.constraints.polytope_ir import ConstraintProgram
from prsc.constraints.values import DIMENSIONS, ObjectValue
from prsc.errors import PrscError
from prsc.geometry.polygon import polygon_points
from prsc.geometry.rotations import yaw_matrices
from prsc.sampling.candidate_plan import CandidateObject, CandidatePlan
from prsc.sampling.candidate_regions import AffineRows, Region
from prsc.sampling.candidate_rules import support
from prsc.sampling.candidate_values import CandidateState
from prsc.sampling.collisions import collide_pairs
from prsc.sampling.counter_stream import candidate_keys, scene_keys, uniforms
from prsc.sampling.engine import SceneResult
from prsc.sampling.prepared import TOL
from prsc.sampling.runtime import ObjectRuntime, evaluate_params
from prsc.sampling.seeds import scene_rng
from prsc.sampling.stats import RejectionStats

# Candidates a scene may draw before it is left to the Gibbs sampler. A scene keeps its first
# passing candidate by number, so how the budget is cut into rounds changes the cost, never
# the scene: rounds start near the number of candidates scenes have needed so far (few where
# the first candidate mostly passes, as in shelf_bin; about 100 in bin_picking) and double.
BUDGET = 468
FIRST_ROUND = (4, 128)  # bounds of the first round's size
CHUNK = 64  # scenes evaluated together: memory grows with CHUNK * 2 * FIRST_ROUND[1] rows at most, not with n
Drawn = Union[SceneResult, PrscError, None]  # a scene, the error of its properties, or None: no candidate passed
# The pilot that decides whether candidate rounds pay (CandidateSampler.pays): where most scenes
# would spend the whole budget and then need the Gibbs sampler anyway (ten cubes in a tray:
# one candidate in about 5,800 passes), the budget is waste and the spec is left to Gibbs sweeps.
PILOT_SEED, PILOT_SCENES = 0x5EED_0F_C4_4D1DA7E5, 8
REJECTED = "candidate"  # the rejection statistics' cause for candidates that failed a test
_EYE = np.eye(3)


@dataclass(frozen=True)
class Pilot:
    """What the pilot found: of `scenes` scenes, how many found a passing candidate among their first `size`,
    and the candidates they drew (up to the first passing one)."""

    scenes: int
    passed: int
    drawn: int
    size: int

    @property
    def pays(self) -> bool:
        """Whether at least half the scenes found a passing candidate (else most would spend the budget)."""
        return 2 * self.passed >= self.scenes


class CandidateSampler:
    """Draws scenes of a candidate plan: the first passing candidate of each, or None for Gibbs."""

    def __init__(self, plan: CandidatePlan, cprog: ConstraintProgram, runtimes: Sequence[ObjectRuntime]) -> None:
        self.plan = plan
        self.cprog = cprog
        self.runtimes = runtimes
        self._soft_site = 4 * len(plan.objects)  # even sites 4k are the objects' centres, odd ones the draws'
        self._upright = {item.name: item.upright for item in plan.objects}
        self._kept = self._needed = 0  # scenes kept and the candidates they needed: the next rounds' sizes
        self._after: dict[int, list] = {}
        for last, test in plan.requires:
            self._after.setdefault(last, []).append(test)

    def draw(self, seed: int, indices: Sequence[int]) -> list[Drawn]:
        """Scenes `indices` of `seed`; None where no candidate passed (draw that scene by Gibbs sweeps),
        the error where the passing candidate's properties are not valid (raise it for that scene only)."""
        out: list[Drawn] = []
        for first in range(0, len(indices), CHUNK):
            out += self._chunk(seed, list(indices[first:first + CHUNK]))
        return out

    def _chunk(self, seed: int, indices: list[int]) -> list[Drawn]:
        keys = scene_keys(seed, np.asarray(indices, dtype=np.uint64))
        results: list[Drawn] = [None] * len(indices)
        pending = np.arange(len(indices))
        first = 0  # the round's first candidate number
        size = self._first_round()
        while len(pending) and first < BUDGET:
            size = min(size, BUDGET - first)
            state, ok = self.evaluate(candidate_keys(keys[pending], first, size), keys[pending])
            ok = ok.reshape(len(pending), size)
            passed = ok.any(axis=1)
            tried = ok.argmax(axis=1)[passed]  # each passing scene's first passing candidate in this round
            rows = np.flatnonzero(passed) * size + tried
            for scene, row, tried_before in zip(pending[passed], rows, tried):
                try:
                    results[scene] = self._result(state, int(row), seed, indices[scene], first + int(tried_before))
                except PrscError as error:  # a property this scene cannot have: reported when the scene is asked for
                    results[scene] = error
            self._kept += int(passed.sum())
            self._needed += int((first + tried + 1).sum())
            pending = pending[~passed]
            first += size
            size = min(2 * size, 2 * FIRST_ROUND[1])
        return results

    def pilot(self, sizes: tuple[int, ...] = (16, BUDGET)) -> "Pilot":
        """8 scenes of a fixed pilot seed, `sizes[0]` candidates each, then the next size unless half found one (a
        function of the spec alone, so every run decides the same): how many found a passing candidate, and the
        candidates they drew. `(BUDGET,)`: what every scene would draw, for a cost."""
        keys = scene_keys(PILOT_SEED, np.arange(PILOT_SCENES, dtype=np.uint64))
        for size in sizes:  # most specs decide on the small pilot
            _, ok = self.evaluate(candidate_keys(keys, 0, size), keys)
            ok = ok.reshape(PILOT_SCENES, size)
            passed = ok.any(axis=1)
            if 2 * int(passed.sum()) >= PILOT_SCENES or size == BUDGET:
                drawn = np.where(passed, ok.argmax(axis=1) + 1, size)  # a scene none passed drew them all
                return Pilot(PILOT_SCENES, int(passed.sum()), int(drawn.sum()), size)
        raise AssertionError("unreachable: the last pilot size is BUDGET")

    def _first_round(self) -> int:
        """About 1.5 times the candidates a scene has needed on average so far (cost only: see BUDGET)."""
        mean = self._needed / self._kept if self._kept else FIRST_ROUND[0]
        return int(min(max(1.5 * mean, FIRST_ROUND[0]), FIRST_ROUND[1]))

    def evaluate(self, keys: np.ndarray, scenes: np.ndarray) -> tuple[CandidateState, np.ndarray]:
        """Every candidate of `keys` drawn and tested: (its state, which passed). `scenes`: the keys of
        their scenes, each scene's candidates consecutive."""
        state = CandidateState(keys)
        n = len(keys)
        ok = np.ones(n, dtype=bool)
        if len(self.plan.soft):
            # Which soft requires a scene enforces is drawn once per scene, as the sequential sampler
            # does: `require[p]` holds in a fraction p of scenes, whatever its candidates did.
            active = uniforms(scenes, self._soft_site, len(self.plan.soft)) < self.plan.soft
            state.active = np.repeat(active, n // len(scenes), axis=0)
        for test in self._after.get(-1, ()):
            ok &= test(state)
        for k, item in enumerate(self.plan.objects):
            ok &= draw_box(item, k, state)
            # The box's axis-aligned half extents, for the broad phase of later pairs too.
            state.reaches[item.name] = np.einsum("nij,nj->ni", np.abs(state.rotations[item.name]), state.dims[item.name] * 0.5)
            if item.obstacles:
                alive = np.flatnonzero(ok)  # only candidates still standing are tested
                for other in item.obstacles:
                    alive = alive[~_collide(state, item.name, other, alive, item.upright and self._upright[other])]
                ok[:] = False
                ok[alive] = True
            for test in self._after.get(k, ()):
                ok &= test(state)
        return state, ok

    def _result(self, state: CandidateState, row: int, seed: int, index: int, rejected: int) -> SceneResult:
        """The scene of one passing candidate, as the sequential sampler returns it (draws memoised;
        properties no test read are drawn from the scene's own Generator)."""
        ctx = SceneContext(scene_rng(seed, index))
        for draw_id, values in state.draws.items():
            ctx.draws[draw_id] = float(values[row if len(values) > 1 else 0, 0])
        objects = []
        for rt in self.runtimes:
            plan = rt.plan
            dims = tuple(float(v) for v in state.dims[plan.name][row])
            props = dict(plan.static_props)
            props.update(zip(DIMENSIONS, dims))
            obj = ObjectValue(plan.name, plan.class_name, plan.span, np.array(state.positions[plan.name][row]),
                              np.array(state.rotations[plan.name][row]), dims, props, plan.property_fns)
            ctx.objects[plan.name] = obj
            objects.append(obj)
        ctx.level = len(objects)
        for rt, obj in zip(self.runtimes, objects):
            rt.finish(obj, ctx)
        if len(self.plan.soft):
            assert state.active is not None
            ctx.active_requires = frozenset(int(i) for i in np.flatnonzero(state.active[row]))
        stats = RejectionStats(scenes=1)
        if rejected:
            stats.add(REJECTED, rejected)
        return SceneResult(objects, evaluate_params(self.cprog, ctx), stats, ctx)


def draw_box(item: CandidateObject, site: int, state: CandidateState) -> np.ndarray:
    """Each candidate's box of one object (the `site`th of its plan) drawn into `state`: size and yaw from
    their priors, the centre uniform on its region given the earlier objects; which regions were not empty."""
    n = len(state.keys)
    dims = state.dims[item.name] = np.empty((n, len(item.sizes)))
    for j, size in enumerate(item.sizes):  # each (n, 1), or (1, 1) where it is the same for all
        dims[:, j] = np.ravel(size.fn(state))
    state.rotations[item.name] = _rotations(item, state, n)
    position, valid = _draw(item.region, item.name, state, uniforms(state.keys, 4 * site, item.region.uniforms))
    state.positions[item.name] = position
    if item.toward is not None:
        state.rotations[item.name] = _facing(np.broadcast_to(item.toward.fn(state), (n, 3)) - position)
    return valid


def _rotations(item: CandidateObject, state: CandidateState, n: int) -> np.ndarray:
    if item.yaw is None:
        return np.broadcast_to(item.rotation, (n, 3, 3))
    return yaw_matrices(np.broadcast_to(item.yaw.fn(state), (n, 1))[:, 0])


def _facing(direction: np.ndarray) -> np.ndarray:
    """`facing toward`: the yaw turning local +y toward the direction's horizontal part, none when it
    has none (orientation.rotation_from and rotations.yaw_toward)."""
    flat = np.hypot(direction[:, 0], direction[:, 1]) == 0.0
    return yaw_matrices(np.where(flat, 0.0, np.arctan2(-direction[:, 0], direction[:, 1])))


def _draw(region: Region, name: str, state: CandidateState, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Candidate centres uniform on their regions, and which regions are not empty."""
    n = len(u)
    valid = np.ones(n, dtype=bool)
    if region.kind == "fixed":
        if region.point is not None:
            return np.broadcast_to(region.point, (n, 3)), valid
        assert region.sampler is not None
        return region.sampler.points(u), valid
    if region.at is not None:
        assert region.rows is not None
        point = np.array(np.broadcast_to(region.at.fn(state), (n, 3)))
        rows = region.rows
        valid = np.all(point @ rows.A.T - rows.b <= TOL * np.maximum(np.linalg.norm(rows.A, axis=1), 1.0), axis=1)
        if len(rows.d):
            valid &= np.all(np.abs(point @ rows.C.T - rows.d) <= TOL * np.maximum(np.linalg.norm(rows.C, axis=1), 1.0), axis=1)
        return point, valid
    if region.plane is not None:
        return _on_plane(region, name, state, u)
    assert region.anchor is not None
    if region.affine is not None:
        return _affine_points(region.affine, state.positions[region.anchor], u)
    if region.kind == "carried":
        assert region.sampler is not None
        return region.sampler.points(u) + state.positions[region.anchor], valid
    # A rectangle on the carrier's face or floor, in its frame (specifiers.rows_on's rows).
    pos, rot = state.positions[region.anchor], state.rotations[region.anchor]
    unrotated = rot.strides[0] == 0 and np.array_equal(rot[0], _EYE)  # the same for all: no products
    if unrotated:
        terms = np.abs(state.rotations[name]) * (state.dims[name] * 0.5)[:, None, :]
        s = terms[:, :, 0] + terms[:, :, 1] + terms[:, :, 2]  # support's, exactly (sum(axis=2)'s order, 3x faster)
    else:
        s = support(np.swapaxes(rot, 1, 2), state.rotations[name], state.dims[name] * 0.5)  # along its x, y, up
    hx, hy = np.full(n, region.half_size[0]), np.full(n, region.half_size[1])
    if region.completely:
        hx, hy = hx - s[:, 0], hy - s[:, 1]
        valid = (hx >= 0.0) & (hy >= 0.0)  # the footprint does not fit: an empty region, never drawn
    lift = s[:, 2] + (region.interior.floor_top if region.interior is not None else state.dims[region.anchor][:, 2] * 0.5)
    if region.cuts:
        edges = [(np.full(n, 1.0), np.zeros(n), hx), (np.full(n, -1.0), np.zeros(n), hx),
                 (np.zeros(n), np.full(n, 1.0), hy), (np.zeros(n), np.full(n, -1.0), hy)]
        rows = [np.stack([np.stack(edge, axis=1) for edge in edges], axis=1)]
        rows += _cut_rows(region, state, pos + lift[:, None] * rot[:, :, 2], rot[:, :, 0], rot[:, :, 1])
        xy, inside = polygon_points(np.concatenate(rows, axis=1), u)
        x, y, valid = xy[:, 0], xy[:, 1], valid & inside
    else:
        x, y = (2.0 * u[:, 0] - 1.0) * hx, (2.0 * u[:, 1] - 1.0) * hy
    if unrotated:  # the products below with the identity's columns: adding their zeros changes no bit
        point = np.array(np.broadcast_to(pos, (n, 3)))
        point[:, 0] += x
        point[:, 1] += y
        point[:, 2] += lift
        return point, valid
    return pos + x[:, None] * rot[:, :, 0] + y[:, None] * rot[:, :, 1] + lift[:, None] * rot[:, :, 2], valid


def _cut_rows(region: Region, state: CandidateState, origin: np.ndarray, e1: np.ndarray, e2: np.ndarray) -> list[np.ndarray]:
    """The region's cuts a.p <= b on p = origin + x e1 + y e2 as half-planes (alpha, beta, gamma) in (x, y),
    (n, m, 3) each; e1, e2 per candidate (n, 3) or the same for all (3,)."""
    out = []
    for cut in region.cuts:
        a, b = cut(state)
        along = [a @ e if e.ndim == 1 else np.einsum("nmi,ni->nm", a, e) for e in (e1, e2)]
        out.append(np.stack([along[0], along[1], b - np.einsum("nmi,ni->nm", a, origin)], axis=2))
    return out


def _on_plane(region: Region, name: str, state: CandidateState, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points uniform on a fixed plane's polygon, shrunk by each candidate's footprint, cut per candidate."""
    plane = region.plane
    assert plane is not None
    n = len(u)
    rotation, half = state.rotations[name], state.dims[name] * 0.5
    lift = support(np.broadcast_to(plane.normal, (n, 1, 3)), rotation, half)[:, 0]  # rest on the plane
    across = plane.a @ plane.normal  # the rows' part along the normal: lifting p does not move it in the plane
    gamma = np.broadcast_to(plane.b - plane.offset * across, (n, len(plane.b)))
    if plane.completely:
        in_plane = plane.a - np.outer(across, plane.normal)
        gamma = gamma - support(np.broadcast_to(in_plane, (n,) + in_plane.shape), rotation, half)
    rows = [np.stack([np.broadcast_to(plane.a @ plane.basis[:, 0], gamma.shape),
                      np.broadcast_to(plane.a @ plane.basis[:, 1], gamma.shape), gamma], axis=2)]
    origin = (plane.offset + lift)[:, None] * plane.normal
    rows += _cut_rows(region, state, origin, plane.basis[:, 0], plane.basis[:, 1])
    xy, valid = polygon_points(np.concatenate(rows, axis=1), u)
    return origin + xy @ plane.basis.T, valid


def _affine_points(rows: AffineRows, anchor: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points uniform on each candidate's carried, cut region (a point, segment or polygon in z)."""
    n, k = len(u), rows.basis.shape[1]
    valid = np.all(np.abs(anchor @ rows.residual.T + rows.misfit) <= TOL, axis=1)  # the equalities meet
    b = rows.b_z + anchor @ rows.b_t.T  # (n, m)
    if k == 2:
        z, area = polygon_points(np.concatenate([np.broadcast_to(rows.a_z, b.shape + (2,)), b[:, :, None]], axis=2), u)
        valid &= area
    elif k == 1:
        c = rows.a_z[:, 0]
        upper = np.min(np.where(c > 0, b / np.where(c > 0, c, 1.0), np.inf), axis=1, initial=np.inf)
        lower = np.max(np.where(c < 0, b / np.where(c < 0, c, 1.0), -np.inf), axis=1, initial=-np.inf)
        flat = np.all(np.where(c == 0, b >= -TOL, True), axis=1)
        valid &= (upper > lower) & flat & np.isfinite(upper) & np.isfinite(lower)
        z = (lower + (upper - lower) * u[:, 0])[:, None]
        z = np.where(valid[:, None], z, 0.0)
    else:
        z = np.zeros((n, 0))
        valid &= np.all(b >= -TOL * np.maximum(1.0, np.abs(b)), axis=1)
    return rows.origin + anchor @ rows.shift.T + z @ rows.basis.T, valid


def _collide(state: CandidateState, a: str, b: str, rows: np.ndarray, upright: bool) -> np.ndarray:
    """Which of the candidates `rows` have boxes of a and b that collide (collisions.collide_pairs)."""
    return collide_pairs(state.positions[a][rows], state.rotations[a][rows], state.dims[a][rows] * 0.5,
                         state.positions[b][rows], state.rotations[b][rows], state.dims[b][rows] * 0.5,
                         state.reaches[a][rows] + state.reaches[b][rows], upright)


__all__ = ["BUDGET", "CandidateSampler", "CHUNK", "Pilot"]
