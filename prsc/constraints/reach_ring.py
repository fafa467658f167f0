"""An arm's top-down reach about its base as exact rows: one convex outer cell minus one
convex hole (docs/assets.md, "`reachable by`").

The reach measured along rays from the base (each ray an interval of radii, or none) is
an annulus, perhaps with a gap where the base joint cannot turn. One convex cell cannot
hold an annulus, so the reach is kept as exact rows of three convex cells: the outer cell (under the chord
of every sector's smaller outer radius), less the hole about the base (the hull of the
polygon about every sector's larger inner radius) and less the gap (a wedge from the base
over the sectors without reach). The sampler subtracts the hole and the gap like any
excluded cell.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

Ray = tuple[float, float] | None  # (inner, outer) radius reached along a ray, or none
RING_KEYS = ("A", "b", "hole_A", "hole_b", "gap_A", "gap_b")  # a ring's fields in its JSON, in order


@dataclass(frozen=True)
class ReachRing:
    """Rows (A, b) in the base's frame: the reach is {A p <= b} minus the hole {hole_a p <= hole_b}
    and minus the gap {gap_a p <= gap_b} (the gap repeats the hole when the reach goes all round)."""

    a: np.ndarray
    b: np.ndarray
    hole_a: np.ndarray
    hole_b: np.ndarray
    gap_a: np.ndarray
    gap_b: np.ndarray

    def excluded(self) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
        """The two cells the centre stays out of: the hole and the gap."""
        return (self.hole_a, self.hole_b), (self.gap_a, self.gap_b)


def _direction(angle: float) -> np.ndarray:
    return np.array([math.cos(angle), math.sin(angle)])


def _left(angle: float) -> np.ndarray:
    """The normal turned a quarter anticlockwise from the ray `angle`."""
    return np.array([-math.sin(angle), math.cos(angle)])


def _half_sectors(angles: list[float]) -> list[float]:
    """Half the angle of each sector (ray j to ray j + 1, the last wrapping to the first): pi / n
    for evenly spaced rays, so their rows are what they always were, bit for bit."""
    n = len(angles)
    widths = [(angles[(j + 1) % n] - angles[j]) % (2 * math.pi) for j in range(n)]
    if max(abs(w - 2 * math.pi / n) for w in widths) < 1e-9:
        return [math.pi / n] * n
    return [w / 2 for w in widths]


def _longest_run(reached: list[bool], halves: list[float]) -> list[int]:
    """The circular run of reached sectors of the widest angle, in order."""
    n = len(reached)
    if all(reached):
        return list(range(n))
    start = reached.index(False)
    best: list[int] = []
    run: list[int] = []
    best_width = width = 0.0  # the half angles of `best` and `run`, added in order
    for step in range(1, n + 1):
        j = (start + step) % n
        if reached[j]:
            run.append(j)
            width += halves[j]
            if width > best_width + 1e-12:
                best, best_width = list(run), width
        else:
            run, width = [], 0.0
    return best


def _extended(heights: list[float], radii: list[float], pad: float) -> list[tuple[float, float]]:
    """(height, radius) at each height, and `pad` beyond the first and last along their segments."""
    points = list(zip(heights, radii))
    if len(points) < 2:
        return [(heights[0] - pad, radii[0])] + points + [(heights[0] + pad, radii[0])]
    (za, ra), (zb, rb) = points[0], points[1]
    (zy, ry), (zz, rz) = points[-2], points[-1]
    return ([(za - pad, max(ra - (rb - ra) / (zb - za) * pad, 0.0))] + points
            + [(zz + pad, max(rz + (rz - ry) / (zz - zy) * pad, 0.0))])


def ring_from_rays(angles: list[float], heights: list[float], rays: list[list[Ray]], margin: float,
                   inner_margin: float) -> ReachRing:
    """The ring kept of rays at `angles` (radians about +z from +x, increasing, all the way round;
    evenly spaced but for rays added where the reach ends, as arm_reach does), measured at
    each of `heights` (rays[j][k]: ray j at height k, increasing).

    Sector j lies between rays j and j + 1 (the last wraps to the first) and is reached when
    both rays are at every height. Its outer radius at each height is the rays' smaller one
    less `margin`, its inner radius their larger one plus `inner_margin`; between heights
    both are interpolated linearly. The outer cell holds every sector under its chords (one
    row per pair of heights: exact where the outer radius is concave in the height, inside
    it otherwise); the hole is the hull of the polygons about the inner radii at every
    height (exact where the inner radius is concave, larger otherwise). Only the longest run
    of reached sectors is kept: spanning at most half a turn, the outer cell is cut to its
    angles; spanning more, the rest is the gap, a wedge from the base. The cell spans the
    heights. ValueError when no sector is reached.
    """
    from scipy.spatial import ConvexHull

    n = len(angles)
    halves = _half_sectors(angles)
    z0, z1 = heights[0], heights[-1]
    radii: list[tuple[list[float], list[float]] | None] = []
    for j in range(n):
        pair = (rays[j], rays[(j + 1) % n])
        if any(r is None for ray in pair for r in ray):
            radii.append(None)
            continue
        inner = [max(a[0], b[0]) + inner_margin for a, b in zip(*pair)]  # type: ignore[index]
        outer = [min(a[1], b[1]) - margin for a, b in zip(*pair)]  # type: ignore[index]
        radii.append((inner, outer) if all(o > i for i, o in zip(inner, outer)) else None)
    if not any(radii):
        raise ValueError("the tool reaches no sector between two rays top-down")
    run = _longest_run([r is not None for r in radii], halves)
    far = max(max(radii[j][1]) for j in run)  # type: ignore[index]
    rows: list[list[float]] = []
    offsets: list[float] = []
    corners: list[list[float]] = [[0.0, 0.0, z0 - 0.01], [0.0, 0.0, z1 + 0.01]]
    for j in range(n):
        half = halves[j]
        direction = _direction(angles[j] + half)
        if j not in run:
            rows.append([*direction, 0.0])
            offsets.append(far * math.cos(half))
            continue
        inner, outer = radii[j]  # type: ignore[misc]
        if len(heights) == 1:
            rows.append([*direction, 0.0])
            offsets.append(outer[0] * math.cos(half))
        for k in range(len(heights) - 1):
            slope = (outer[k + 1] - outer[k]) / (heights[k + 1] - heights[k])
            rows.append([*direction, -slope * math.cos(half)])
            offsets.append((outer[k] - slope * heights[k]) * math.cos(half))
        for z, r in _extended(heights, inner, 0.01):
            corner = r / math.cos(half)
            corners += [[*(corner * _direction(angles[j])), z], [*(corner * _direction(angles[(j + 1) % n])), z]]
    equations = ConvexHull(np.array(corners)).equations  # n . x + c <= 0 inside
    hole = (equations[:, :3], -equations[:, 3])
    gap = hole
    if len(run) < n:
        first, last = angles[run[0]], angles[run[-1]] + 2 * halves[run[-1]]
        if sum(2 * halves[j] for j in run) <= math.pi + 1e-9:  # the run is convex: cut the outer cell to it
            rows += [[*-_left(first), 0.0], [*_left(last), 0.0]]
            offsets += [0.0, 0.0]
        else:  # the rest is a wedge of less than half a turn: anticlockwise of `last`, clockwise of `first`
            gap = (np.array([[*-_left(last), 0.0], [*_left(first), 0.0]]), np.zeros(2))
    rows += [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]
    offsets += [z1, -z0]
    return ReachRing(np.array(rows, dtype=float), np.array(offsets, dtype=float), *hole, *gap)


def ring_json(ring: ReachRing) -> dict[str, list]:
    """The ring's rows as JSON lists under RING_KEYS."""
    return dict(zip(RING_KEYS, (x.tolist() for x in (ring.a, ring.b, ring.hole_a, ring.hole_b, ring.gap_a, ring.gap_b))))


def ring_from_json(data: dict) -> ReachRing:
    """The ring `ring_json` wrote (other keys of `data` are ignored)."""
    return ReachRing(*(np.array(data[key], dtype=float) for key in RING_KEYS))


def contains(ring: ReachRing, points: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """Which points (rows, base frame) lie in the ring: in the outer cell and in no excluded cell's interior."""
    points = np.atleast_2d(points)
    inside = np.all(points @ ring.a.T <= ring.b + tol, axis=1)
    for a, b in ring.excluded():
        inside &= ~np.all(points @ a.T < b - tol, axis=1)
    return inside
