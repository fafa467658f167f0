"""`reachable by R` for an arm from a file (docs/assets.md): the points its tool reaches
top-down, computed from the arm's own kinematics as a ring of exact rows (an outer convex
cell less a hole and a gap, prsc/constraints/reach_ring.py) and cached by the file's content
and tool frame in the build folder (`$PRSC_BUILD_DIR/reach/<key>-<tool>-v<recipe>.json`), so a
second compile costs nothing.

Top-down means the tool frame's +z (the flange normal of a URDF arm's last link, or the
`tcp` site's z) points straight down, any yaw. A point counts as reached when the one IK
(prsc/user_assets/arm_ik.py, mink on the arm's MuJoCo model) brings the tool there within 2 mm
and 0.02 rad, and also 12 cm above it (the approach), by poses that keep the arm above its base
and out of itself. Along each ray from the base (SECTORS all the way
round, in the object's axes: the file's +x, the ROS forward, turned to the object's ahead,
+y, by asset_spec) and at each height (HEIGHTS
above the root's origin) the reachable radii are scanned every STEP and both ends bisected
to 3 mm. Each bound is then shrunk by a margin: between two rays the reach is taken to be
no less than at the nearer of them, less the margin. Last, the hole's edge is checked by the
IK from home (VERIFY_*) and grown where it misses.
"""

from __future__ import annotations

import bisect
import hashlib
import json
import math
import os
import re
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from prsc.user_assets.arm_ik import REACH_APPROACH, RESTARTS, ArmFrames, reach_top_down, turned
from prsc.user_assets.asset_files import ArticulatedAsset, asset_spec, build_root
from prsc.files import atomic_write, building
from prsc.constraints.reach_ring import ReachRing, contains, ring_from_json, ring_from_rays, ring_json

RECIPE_VERSION = "12"  # 12: the hole's edge checked by the IK from home and grown where it misses (VERIFY_*). 11: the one IK, mink's (prsc/user_assets/arm_ik.py), which refuses poses that put a link into another (ArmFrames.fits, the one self-collision test); the inner end sought with restarts too. 9: the model turned to face the object's +y (asset_files.FORWARD_YAW). The IK, the construction below and the model it reads (asset_spec)
APPROACH = REACH_APPROACH  # m above the point the tool must also reach
HEIGHTS = (0.0, 0.075, 0.15)  # m above the root origin: the levels the cell spans
SECTORS = 36  # rays all the way round: every 10 degrees
STEP = 0.05  # m between radii of the coarse scan
RADII = tuple(round(STEP * (i + 1), 3) for i in range(30))  # the coarse scan, m
REFINE = 4  # bisections of each end (5 cm / 2^4 ~ 3 mm)
EDGE_REFINE = 4  # bisections of the angle where the reach ends between two rays (10 degrees / 2^4)
EDGE_TOLERANCE = 0.01  # m an added ray's run may fall short of its reached neighbour's at either end
# m taken off the outer radii and added to the inner ones. The chords under the outer radii
# already lie inside them, and the hole's polygon holds the circle of each inner radius, so
# the margins only cover the reach changing between two rays: on a 1 cm grid over the band
# these give up against the 6 and 10 mm before them, every point is reached top-down (the
# xArm6, the KUKA iiwa and the tests' MJCF arm, 2026-11-26; docs/assets.md).
MARGIN = 0.003
INNER_MARGIN = 0.005
INNER_CHECK = 0.005  # m steps outwards from an inner end a controller's IK does not find
# Beside the base the IK from home is ragged: between two rays whose inner ends it reaches it
# may miss points farther out (the library's 7-joint arm: 34 of 1,252 points within 2 cm of the hole's edge at
# its root's height, 0.19-0.23 m from its base). So the built ring's hole edge is checked, in
# VERIFY_ANGLES directions at every height and VERIFY_BAND outwards from it, by the IK as a
# controller runs it, and where a kept point is missed a ray is added there whose inner end lies
# beyond it; then checked again, up to VERIFY_ROUNDS times.
VERIFY_ANGLES = 180  # every 2 degrees
VERIFY_BAND = (0.0, 0.01, 0.02)  # m outwards from the hole's edge
VERIFY_ROUNDS = 6


@dataclass(frozen=True)
class ArmReach:
    """The reach's rows about the arm's root in its object's axes, and the rays they were built from."""

    ring: ReachRing
    rays: tuple[tuple[float, float, float | None, float | None], ...]  # (height, angle, inner, outer)


class TopDownIK:
    """The arm alone (its file's model, turned as its object), asked whether its tool reaches
    points top-down (about its root, in its object's axes)."""

    def __init__(self, asset: ArticulatedAsset) -> None:
        import mujoco

        self.model = asset_spec(asset.source, (), asset.fitting).compile()
        self.root_name = asset.root
        self.data = mujoco.MjData(self.model)
        self.arm = ArmFrames.of(self.model, [j.name for j in asset.joints], str(asset.tcp))
        self.home = np.array([j.home for j in asset.joints])
        self.data.qpos[self.arm.qpos] = self.home
        mujoco.mj_kinematics(self.model, self.data)
        self.root = self.data.xpos[self.model.body(asset.root).id].copy()
        self.heading = self.arm.heading(self.data, self.root)  # where the tool points at home

    def reaches(self, point: np.ndarray, seed: np.ndarray, restarts: int = 0) -> tuple[np.ndarray, bool]:
        """Whether the tool reaches the point (root frame) and the approach above it, top-down,
        from `seed`, else from home turned towards the point (and that bent), else from `restarts`
        more; a pose with one link in another is no reach (the one IK's ArmFrames.fits)."""
        home = self.turned(math.atan2(point[1], point[0]))
        return reach_top_down(self.model, self.data, self.arm, point + self.root, seed, home, APPROACH, restarts)

    def turned(self, azimuth: float) -> np.ndarray:
        """Home with the first joint turned so that the tool heads towards `azimuth`."""
        return turned(self.home, self.arm, self.heading, azimuth)

    def reaches_from_home(self, point: np.ndarray) -> bool:
        """Whether the tool reaches the point top-down from home turned towards it (and that bent)."""
        return self.reaches(point, self.turned(math.atan2(point[1], point[0])), RESTARTS)[1]

    def span(self) -> float:
        """An upper bound of the tool's distance from the root: the chain's offsets added up."""
        model = self.model
        body = self.arm.tool
        total = 0.0
        if self.arm.tool_is_site:
            total, body = float(np.linalg.norm(model.site_pos[body])), int(model.site_bodyid[body])
        root = self.model.body(self.root_name).id
        while body not in (root, 0):
            total += float(np.linalg.norm(model.body_pos[body]))
            body = int(model.body_parentid[body])
        return total


def _ray_point(angle: float, radius: float, height: float) -> np.ndarray:
    """The point at `radius` along the ray `angle` (0: the object's +x, its right; pi/2: ahead, +y)."""
    return np.array([radius * math.cos(angle), radius * math.sin(angle), height])


def _bisect(ik: TopDownIK, angle: float, height: float, inside: float, outside: float, q: np.ndarray,
            restarts: int = 0) -> float:
    """The reached radius nearest the boundary between `inside` (reached from q) and `outside`."""
    for _ in range(REFINE):
        mid = (inside + outside) / 2
        q_mid, ok = ik.reaches(_ray_point(angle, mid, height), q, restarts)
        if ok:
            inside, q = mid, q_mid
        else:
            outside = mid
    return inside


def _ray(ik: TopDownIK, angle: float, height: float) -> tuple[float, float] | None:
    """The longest run of reachable radii along a ray, both ends refined; None if none.

    Outwards from home every STEP up to the arm's span, then inwards from the run's first
    radius, each IK started from the last solution (from home alone the IK misses points
    near the base). A run ends only where RESTARTS more starts fail too (a 7-joint arm's IK
    stalls at points it reaches); before a run, where most points fail, they are spared.
    The longest run, not the first: beside the base a few radii may be reached apart from
    the rest (robosuite's Sawyer reached 0.10 m, then nothing to 0.4 m, then on to 1 m),
    and a sector keeps the smaller of its rays' runs."""
    radii = [radius for radius in RADII if radius <= ik.span() + STEP]
    runs: list[tuple[list[float], np.ndarray, np.ndarray]] = []  # radii, first and last solution
    for restarts in (0, RESTARTS):
        q = ik.turned(angle)
        run: list[float] = []
        first_q = last_q = q
        for radius in radii:
            if not run and runs and radii[-1] - radius <= max(r[-1] - r[0] for r, _, _ in runs):
                break  # what is left of the ray could not hold a longer run
            point = _ray_point(angle, radius, height)
            q_new, ok = ik.reaches(point, q, RESTARTS if run else restarts)
            if ok:
                if not run:
                    first_q = q_new
                run.append(radius)
                q = last_q = q_new
            elif run:
                runs.append((run, first_q, last_q))
                run, q = [], ik.turned(angle)
        if run:
            runs.append((run, first_q, last_q))
        if runs:
            break
    if not runs:
        return None
    run, first_q, last_q = max(runs, key=lambda found: found[0][-1] - found[0][0])
    outer = _bisect(ik, angle, height, run[-1], run[-1] + STEP, last_q)
    inner, q = run[0], first_q
    while inner - STEP / 2 > 0:  # inwards too, the run ends only where RESTARTS more starts fail
        q_new, ok = ik.reaches(_ray_point(angle, inner - STEP / 2, height), q, RESTARTS)
        if not ok:
            break
        inner, q = inner - STEP / 2, q_new
    if inner - STEP / 2 > 0:
        inner = _bisect(ik, angle, height, inner, inner - STEP / 2, q, RESTARTS)
    # The inner end as a controller seeks a pose (from home turned towards the point, then
    # RESTARTS more): one found only by walking inwards from the last solution it does not find.
    while inner < run[0] and not ik.reaches_from_home(_ray_point(angle, inner, height)):
        inner = min(inner + INNER_CHECK, run[0])
    return inner, outer


def ray_angles() -> list[float]:
    """The rays' directions, all the way round from the object's -x (radians, 0 its +x, pi/2 ahead)."""
    return [-math.pi + 2 * math.pi * j / SECTORS for j in range(SECTORS)]


def _rays_at(ik: TopDownIK, angle: float) -> list:
    """The ray `angle` at every height (an (inner, outer) pair or None at each)."""
    return [_ray(ik, angle, height) for height in HEIGHTS]


def _edges(ik: TopDownIK, angles: list[float], per_ray: list[list]) -> dict[float, list]:
    """Rays added where the reach ends between two rays (a base joint's limit): between a ray
    reached at every height and a neighbour that is not, the angle is bisected EDGE_REFINE
    times, keeping the last ray that reaches as far in and out as the reached one (within
    EDGE_TOLERANCE) at every height: a sector keeps the smaller run of its two rays, and near
    the limit a ray reaches only a sliver. Without them the gap would take both sectors about
    a ray at the limit (40 degrees behind an arm whose base turns +-170)."""
    n = len(angles)
    full = [all(r is not None for r in rays) for rays in per_ray]
    added: dict[float, list] = {}
    for j in range(n):
        following = (j + 1) % n
        if full[j] == full[following]:
            continue
        end = angles[j] + (angles[following] - angles[j]) % (2 * math.pi)
        inside, outside = (angles[j], end) if full[j] else (end, angles[j])
        reached = per_ray[j] if full[j] else per_ray[following]
        kept = None
        for _ in range(EDGE_REFINE):
            middle = (inside + outside) / 2
            rays = _rays_at(ik, middle)
            if all(r is not None and r[0] <= ref[0] + EDGE_TOLERANCE and r[1] >= ref[1] - EDGE_TOLERANCE
                   for r, ref in zip(rays, reached)):
                inside, kept = middle, rays
            else:
                outside = middle
        if kept is not None:
            added[(inside + math.pi) % (2 * math.pi) - math.pi] = kept
    return added


def _ring(by_angle: dict[float, list]) -> ReachRing:
    """The ring of the rays measured so far (ring_from_rays with this builder's margins)."""
    angles = sorted(by_angle)
    try:
        return ring_from_rays(angles, list(HEIGHTS), [by_angle[angle] for angle in angles], MARGIN, INNER_MARGIN)
    except ValueError as error:
        raise ValueError(f"{error} (rays every {360 // SECTORS} degrees at heights {list(HEIGHTS)} m)") from None


def _hole_edge(ring: ReachRing, angle: float, height: float) -> float:
    """How far from the root, along the direction `angle` at `height`, the ring's hole ends."""
    rate = ring.hole_a[:, :2] @ np.array([math.cos(angle), math.sin(angle)])
    room = ring.hole_b - ring.hole_a[:, 2] * height
    ahead = rate > 1e-12
    return float(np.min(room[ahead] / rate[ahead]))


def _hole_misses(ik: TopDownIK, ring: ReachRing, known: dict[tuple, bool]) -> dict[tuple[float, int], float]:
    """Points the ring keeps within VERIFY_BAND of its hole's edge that the IK does not reach
    from home: per (direction, height index), the farthest such radius. `known` holds the
    answers of earlier rounds (a round moves the edge in a few directions only)."""
    misses: dict[tuple[float, int], float] = {}
    for angle in (-math.pi + 2 * math.pi * i / VERIFY_ANGLES for i in range(VERIFY_ANGLES)):
        for k, height in enumerate(HEIGHTS):
            edge = _hole_edge(ring, angle, height) + 1e-4  # just outside the hole
            for radius in (edge + step for step in VERIFY_BAND):
                point = _ray_point(angle, radius, height)
                if not contains(ring, point)[0]:
                    continue
                key = (angle, k, round(radius, 9))
                if key not in known:
                    known[key] = ik.reaches_from_home(point)
                if not known[key]:
                    misses[(angle, k)] = radius
    return misses


def _grow_hole(by_angle: dict[float, list], misses: dict[tuple[float, int], float]) -> None:
    """Rays added (or moved) where the hole's edge was missed: a ray between two measured ones
    claims no more than the sector it splits (their larger inner and smaller outer radius), and
    at the height of a miss its inner end lies INNER_CHECK beyond it."""
    measured = sorted(by_angle)
    for (angle, k), radius in sorted(misses.items()):
        same = [known for known in by_angle if abs(known - angle) < 1e-9]
        if same:
            angle = same[0]
        else:
            j = bisect.bisect_right(measured, angle) - 1  # -1: the last ray, round the turn
            pair = (by_angle[measured[j]], by_angle[measured[(j + 1) % len(measured)]])
            by_angle[angle] = [None if a is None or b is None else (max(a[0], b[0]), min(a[1], b[1]))
                               for a, b in zip(*pair)]
        inner, outer = by_angle[angle][k]
        by_angle[angle][k] = (max(inner, radius + INNER_CHECK), outer)


def compute_reach(asset: ArticulatedAsset) -> ArmReach:
    """The arm's top-down reach as a ring of exact rows (some seconds of IK)."""
    ik = TopDownIK(asset)
    angles = ray_angles()
    per_ray = [_rays_at(ik, angle) for angle in angles]
    by_angle = dict(zip(angles, per_ray)) | _edges(ik, angles, per_ray)
    ring = _ring(by_angle)
    known: dict[tuple, bool] = {}
    for _ in range(VERIFY_ROUNDS):
        misses = _hole_misses(ik, ring, known)
        if not misses:
            break
        _grow_hole(by_angle, misses)
        ring = _ring(by_angle)
    angles = sorted(by_angle)
    table = tuple((height, angle, *(by_angle[angle][k] or (None, None)))
                  for k, height in enumerate(HEIGHTS) for angle in angles)
    return ArmReach(ring, table)  # type: ignore[arg-type]


def reach_cache(asset: ArticulatedAsset) -> Path:
    """Where an arm's reach is cached: keyed by the content of every file it reads, its tool
    frame and this recipe."""
    tool = str(asset.tcp)
    tag = re.sub(r"[^A-Za-z0-9_.-]", "_", tool)[:40] + "-" + hashlib.sha256(tool.encode()).hexdigest()[:6]
    return build_root() / "reach" / f"{asset.key}-{tag}-v{RECIPE_VERSION}.json"


def _cached_reach(path: Path, asset: ArticulatedAsset) -> ArmReach | None:
    """The reach a cache file holds, or None when it is missing or cannot be used (unreadable,
    cut short, of other files): such a file is computed again, not trusted."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        if data.get("sha256") != asset.digest:
            return None
        return ArmReach(ring_from_json(data), tuple(tuple(r) for r in data["rays"]))
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None


@lru_cache(maxsize=16)
def arm_reach(asset: ArticulatedAsset) -> ArmReach:
    """The arm's reach, computed on first use and read from the cache after (once per process:
    every scene whose robot moves asks for it three times per `reachable by`)."""
    path = reach_cache(asset)
    cached = _cached_reach(path, asset)
    if cached is not None:
        return cached
    path.parent.mkdir(parents=True, exist_ok=True)
    with building(path):  # compile workers asking at once: one builds (10-25 CPU s), the others read it
        cached = _cached_reach(path, asset)
        if cached is not None:
            return cached
        reach = compute_reach(asset)
        _write_reach(path, asset, reach)
    return reach


def _write_reach(path: Path, asset: ArticulatedAsset, reach: ArmReach) -> None:
    atomic_write(path, json.dumps({
        "asset": os.path.basename(asset.source), "sha256": asset.digest,
        "frame": "the arm's object's axes about its root body: +y ahead (the file's +x), +z up",
        "reach": "A p <= b, and neither hole_A p < hole_b nor gap_A p < gap_b",
        **ring_json(reach.ring),
        "rays": [list(r) for r in reach.rays],
    }, indent=1) + "\n")
