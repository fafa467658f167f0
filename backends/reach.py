"""The Panda's top-down reachable set, from its kinematics: the data `reachable by` reads.

`python -m prsc.backends.reach` (or `make reach`) regenerates
prsc/constraints/reach/panda.json. The constraint stage reads that file and never
imports MuJoCo; tests/constraints/test_reach.py checks the file against the IK.

Reachable means what the handover controller needs (backends/runner/episode.py): with
the gripper pointing down as at home, the tool centre reaches the point, the point 12 cm
above it (the approach) and 15 cm above it (the lift), each IK solved from the previous
one as the controller does. Along each ray from the base (24 directions) and at each
height (5 levels) the reachable radii are scanned every 5 cm and the ends bisected to
3 mm. A cell (a height band times a 15 degree sector) keeps the radii reachable on all
four of its corner rays, shrunk by a margin, as a convex prism: the trapezoid between
the chord of the outer arc and the tangent chord outside the inner arc. The cells are
an inner approximation of a set that is an annulus, not convex.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

APPROACH = 0.12  # m: the controller's approach height above the grasp point
LIFT = 0.15  # m: the controller's lift
HEIGHTS = (-0.05, 0.05, 0.15, 0.25, 0.35)  # m above the base: the levels the cells span
SECTORS = 24
RADII = tuple(round(0.1 + 0.05 * i, 3) for i in range(19))  # the coarse scan, m
REFINE = 4  # bisections of each end of the reachable run (5 cm / 2^4 ~ 3 mm)
MARGIN = 0.01  # m taken off each end of a cell's radial interval
CELL_LEVELS = (0, 1, 2)  # the heights (indices) the one convex cell spans: -5 cm to +15 cm about the base

OUTPUT = Path(__file__).resolve().parent.parent / "prsc" / "constraints" / "reach" / "panda.json"


class TopDownReach:
    """Whether the Panda's tool centre reaches points top-down (base frame: +y ahead, z up)."""

    def __init__(self) -> None:
        from prsc.assets import panda
        from prsc.backends.runner.ik import ArmIK

        self.ik = ArmIK(np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0]))
        self.home = np.array(panda.HOME_QPOS)
        self.down = self.ik.tcp_pose(self.home)[1]

    def reaches(self, point: np.ndarray) -> bool:
        """Approach from home, then the point, then the lift, each from the previous solution."""
        up = np.array([0.0, 0.0, 1.0])
        q = self.home
        for target in (point + APPROACH * up, point, point + LIFT * up):
            solution = self.ik.solve(np.asarray(target, float), self.down, q)
            if not solution.reached:
                return False
            q = solution.q
        return True


def _angles() -> list[float]:
    """Ray directions, -180 to +180 degrees (the last repeats the first)."""
    return [2 * math.pi * j / SECTORS - math.pi for j in range(SECTORS + 1)]


def _ray_point(angle: float, radius: float, height: float) -> np.ndarray:
    """The point at `radius` along the ray `angle` (0: ahead, +y; positive towards -x) at `height`."""
    return np.array([-radius * math.sin(angle), radius * math.cos(angle), height])


def ray_interval(reach: TopDownReach, angle: float, height: float) -> tuple[float, float] | None:
    """The longest run of reachable radii along one ray, ends refined by bisection; None if none."""
    hits = [reach.reaches(_ray_point(angle, r, height)) for r in RADII]
    best: tuple[int, int] | None = None
    start = None
    for i, hit in enumerate(hits + [False]):
        if hit and start is None:
            start = i
        elif not hit and start is not None:
            if best is None or i - start > best[1] - best[0]:
                best = (start, i)
            start = None
    if best is None:
        return None
    lo_in, hi_in = RADII[best[0]], RADII[best[1] - 1]
    lo_out = RADII[best[0] - 1] if best[0] > 0 else None
    hi_out = RADII[best[1]] if best[1] < len(RADII) else None
    lo, hi = lo_in, hi_in
    if lo_out is not None:
        a, b = lo_out, lo_in  # a unreachable, b reachable
        for _ in range(REFINE):
            mid = (a + b) / 2
            a, b = (a, mid) if reach.reaches(_ray_point(angle, mid, height)) else (mid, b)
        lo = b
    if hi_out is not None:
        a, b = hi_in, hi_out  # a reachable, b unreachable
        for _ in range(REFINE):
            mid = (a + b) / 2
            a, b = (mid, b) if reach.reaches(_ray_point(angle, mid, height)) else (a, mid)
        hi = a
    return lo, hi


def cell_rows(a0: float, a1: float, r_in: float, r_out: float, z0: float, z1: float) -> tuple[list, list]:
    """Rows A q <= b of the prism: sector [a0, a1], radii [r_in, r_out] (inner approximation), z in [z0, z1]."""
    half = (a1 - a0) / 2
    mid = (a0 + a1) / 2
    rows, offsets = [], []
    # Side walls through the base: the sector between the rays a0 and a1.
    for angle, sign in ((a0, -1.0), (a1, 1.0)):
        direction = _ray_point(angle, 1.0, 0.0)
        normal = sign * np.array([direction[1], -direction[0], 0.0])  # horizontal, across the ray
        if normal @ _ray_point(mid, 1.0, 0.0) > 0:
            normal = -normal
        rows.append(normal)
        offsets.append(0.0)
    radial = _ray_point(mid, 1.0, 0.0)
    # Outer: the chord between the outer arc's ends (inside the circle r_out).
    rows.append(radial)
    offsets.append(r_out * math.cos(half))
    # Inner: the tangent to the circle r_in at the middle angle (outside the inner circle).
    rows.append(-radial)
    offsets.append(-r_in)
    rows += [np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, -1.0])]
    offsets += [z1, -z0]
    return [[float(v) for v in row] for row in rows], [float(v) for v in offsets]


def convex_cell(rays: dict, angles: list[float]) -> tuple[list, list]:
    """One convex cell ahead of the base: y >= the largest inner radius, under every sector's outer chord.

    A point with y >= d is at least d from the base, so past every inner radius <= d; a
    point under sector j's chord is within that sector's outer radius. Spans the heights
    CELL_LEVELS. Sectors wholly behind the line y = d are cut by it and need no chord.
    """
    inner = max(rays[k, j][0] for k in CELL_LEVELS for j in range(SECTORS) if abs(angles[j]) <= math.pi / 2)
    d = inner + MARGIN
    rows, offsets = [[0.0, -1.0, 0.0]], [-d]
    for j in range(SECTORS):
        a0, a1 = angles[j], angles[j + 1]
        if min(abs(a0), abs(a1)) >= math.pi / 2:
            continue
        ends = [rays[k, jj] for k in CELL_LEVELS for jj in (j, j + 1)]
        r_out = min(e[1] for e in ends if e is not None) - MARGIN
        if any(e is None for e in ends) or r_out <= d:
            raise ValueError(f"no reach along the sector {math.degrees(a0):.0f}..{math.degrees(a1):.0f} deg")
        radial = _ray_point((a0 + a1) / 2, 1.0, 0.0)
        rows.append([float(v) for v in radial])
        offsets.append(r_out * math.cos((a1 - a0) / 2))
    z0, z1 = HEIGHTS[CELL_LEVELS[0]], HEIGHTS[CELL_LEVELS[-1]]
    rows += [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]
    offsets += [z1, -z0]
    return rows, [float(v) for v in offsets]


def compute() -> dict:
    """The reachable-set data of the Panda (a few minutes of IK)."""
    reach = TopDownReach()
    angles = _angles()
    rays: dict[tuple[int, int], tuple[float, float] | None] = {}
    for k, height in enumerate(HEIGHTS):
        for j in range(SECTORS):
            rays[k, j] = ray_interval(reach, angles[j], height)
        rays[k, SECTORS] = rays[k, 0]
    cells = []
    for k in range(len(HEIGHTS) - 1):
        for j in range(SECTORS):
            corners = [rays[kk, jj] for kk in (k, k + 1) for jj in (j, j + 1)]
            if any(c is None for c in corners):
                continue
            half = (angles[j + 1] - angles[j]) / 2
            r_in = max(c[0] for c in corners) / math.cos(half) + MARGIN  # type: ignore[index]
            r_out = min(c[1] for c in corners) - MARGIN  # type: ignore[index]
            if r_out * math.cos(half) <= r_in + 1e-3:
                continue
            a, b = cell_rows(angles[j], angles[j + 1], r_in, r_out, HEIGHTS[k], HEIGHTS[k + 1])
            cells.append({"A": a, "b": b, "sector": [angles[j], angles[j + 1]], "radii": [r_in, r_out],
                          "heights": [HEIGHTS[k], HEIGHTS[k + 1]]})
    cell_a, cell_b = convex_cell(rays, angles)
    return {
        "robot": "panda",
        "frame": "the arm's base: origin at the bottom centre of the Robot box, +y ahead, +z up",
        "grasp": f"tool centre at the point, {APPROACH} m and {LIFT} m above it, gripper pointing down as at home",
        "heights": list(HEIGHTS),
        "angles": angles[:SECTORS],
        "rays": [[k, j, *(rays[k, j] or (None, None))] for k in range(len(HEIGHTS)) for j in range(SECTORS)],
        "margin": MARGIN,
        "cells": cells,
        "cell": {"A": cell_a, "b": cell_b, "heights": [HEIGHTS[CELL_LEVELS[0]], HEIGHTS[CELL_LEVELS[-1]]]},
    }


def main() -> None:
    """Regenerate the data file."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--output", default=str(OUTPUT), help=f"where to write (default {OUTPUT})")
    args = parser.parse_args()
    data = compute()
    Path(args.output).write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    print(f"{len(data['cells'])} cells written to {args.output}")


if __name__ == "__main__":
    main()
