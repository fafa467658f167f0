"""The Panda's top-down reachable set, from its kinematics: the data `reachable by` reads.

`python -m prsc.commands.reach` (`make reach`) regenerates
prsc/constraints/panda_reach.json. The constraint stage reads that file and never
imports MuJoCo; tests/constraints/test_reach.py checks the file against the IK. (A
command, not a backend: it drives the runner's IK and, for the tray report, samples a spec.)

Reachable means what the handover controller needs (backends/runner/handover.py): with
the gripper pointing down as at home, the tool centre reaches the point, the point 12 cm
above it (the approach) and 15 cm above it (the lift), each IK solved from the previous
one as the controller does. Along each ray from the base (24 directions, every 15
degrees) and at each height (HEIGHTS) the longest run of reachable radii is scanned every
5 cm and its ends bisected to 3 mm.

The reachable set is an annulus about the base, not convex. prsc keeps one convex cell
inside it (convex_cell): the half-plane ahead of the base beyond the largest inner
radius, cut by the chord of every sector's outer radius, over the heights CELL_LEVELS,
each bound shrunk by a margin. docs/sampling.md reports how much of a tray it keeps
(`--tray-report SPEC` measures it against the IK on a grid).
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from prsc.files import atomic_write
from prsc.geometry.rotations import quat_to_matrix

APPROACH = 0.12  # m: the controller's approach height above the grasp point
LIFT = 0.15  # m: the controller's lift
HEIGHTS = (-0.05, 0.0, 0.05, 0.15, 0.25, 0.35)  # m above the base: the levels the cells span
SECTORS = 24
RADII = tuple(round(0.1 + 0.05 * i, 3) for i in range(19))  # the coarse scan, m
REFINE = 4  # bisections of each end of the reachable run (5 cm / 2^4 ~ 3 mm)
MARGIN = 0.01  # m taken off the outer radii
INNER_MARGIN = 0.03  # m added to the inner radius: near the base the IK fails in scattered spots
CELL_LEVELS = (1, 2, 3)  # the heights (indices) the one convex cell spans: 0 to 15 cm above the base

OUTPUT = Path(__file__).resolve().parent.parent / "constraints" / "panda_reach.json"


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
    lo = _boundary(reach, angle, height, lo_in, RADII[best[0] - 1]) if best[0] > 0 else lo_in
    hi = _boundary(reach, angle, height, hi_in, RADII[best[1]]) if best[1] < len(RADII) else hi_in
    return lo, hi


def _boundary(reach: TopDownReach, angle: float, height: float, inside: float, outside: float) -> float:
    """The reachable radius nearest the boundary between a reachable and an unreachable radius (bisection)."""
    for _ in range(REFINE):
        mid = (inside + outside) / 2
        if reach.reaches(_ray_point(angle, mid, height)):
            inside = mid
        else:
            outside = mid
    return inside


def convex_cell(rays: dict, angles: list[float]) -> tuple[list, list]:
    """One convex cell ahead of the base: y >= the largest inner radius, under every sector's outer chord.

    A point with y >= d is at least d from the base, so past every inner radius <= d; a
    point under sector j's chord is within that sector's outer radius. Spans the heights
    CELL_LEVELS. Sectors wholly behind the line y = d are cut by it and need no chord.
    """
    inner = max(rays[k, j][0] for k in CELL_LEVELS for j in range(SECTORS) if abs(angles[j]) <= math.pi / 2)
    d = inner + INNER_MARGIN
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
    cell_a, cell_b = convex_cell(rays, angles)
    return {
        "robot": "panda",
        "frame": "the arm's base: origin at the bottom centre of the Robot box, +y ahead, +z up",
        "grasp": f"tool centre at the point, {APPROACH} m and {LIFT} m above it, gripper pointing down as at home",
        "heights": list(HEIGHTS),
        "angles": angles[:SECTORS],
        "rays": [[k, j, *(rays[k, j] or (None, None))] for k in range(len(HEIGHTS)) for j in range(SECTORS)],
        "margin": MARGIN,
        "inner_margin": INNER_MARGIN,
        "cell": {"A": cell_a, "b": cell_b, "heights": [HEIGHTS[CELL_LEVELS[0]], HEIGHTS[CELL_LEVELS[-1]]]},
    }


def tray_report(spec: str, tray: str, cube: str, robot: str, step: float = 0.02) -> dict:
    """How much of a tray the cell keeps, against the IK on a grid of cube centres.

    Grid over the cube centres `completely on` the tray allows (scene 0 of seed 0), every
    `step` metres: the fraction in the cell, the fraction the IK reaches, and the
    fraction of the reachable ones the cell keeps (and any cell point the IK misses).
    """
    from prsc.constraints.reach import reach_cell
    from prsc.sampling import compile_sampler

    scene = compile_sampler(spec).scene(0, 0)
    objects = {o["name"]: o for o in scene["objects"]}
    rot = quat_to_matrix(objects[robot]["quaternion"])
    base = np.asarray(objects[robot]["position"]) - rot[:, 2] * objects[robot]["dimensions"][2] / 2
    centre, dims = np.asarray(objects[tray]["position"]), np.asarray(objects[tray]["dimensions"])
    half_cube = np.asarray(objects[cube]["dimensions"]) / 2
    z = objects[cube]["position"][2]
    a, b = reach_cell(objects[robot]["model"])
    reach = TopDownReach()
    xs = np.arange(centre[0] - dims[0] / 2 + half_cube[0], centre[0] + dims[0] / 2 - half_cube[0] + 1e-9, step)
    ys = np.arange(centre[1] - dims[1] / 2 + half_cube[1], centre[1] + dims[1] / 2 - half_cube[1] + 1e-9, step)
    counts = {"points": 0, "in_cell": 0, "reached": 0, "both": 0}
    for x in xs:
        for y in ys:
            q = rot.T @ (np.array([x, y, z]) - base)
            in_cell, reached = bool(np.all(a @ q <= b)), reach.reaches(q)
            counts["points"] += 1
            counts["in_cell"] += in_cell
            counts["reached"] += reached
            counts["both"] += in_cell and reached
    n = counts["points"]
    return {
        **counts, "step": step,
        "cell_fraction_of_tray": counts["in_cell"] / n,
        "reachable_fraction_of_tray": counts["reached"] / n,
        "reachable_kept_by_cell": counts["both"] / max(counts["reached"], 1),
        "cell_points_not_reached": counts["in_cell"] - counts["both"],
    }


def _reached_area(rays: list, height: float) -> float:
    """The area the tool reaches top-down over the half ahead at `height`, from the rays
    (each sector between two rays an annulus sector with their mean radii)."""
    at = sorted((r[1], r[2], r[3]) for r in rays if r[0] == height and r[2] is not None)
    return sum((b[0] - a[0]) * (((a[2] + b[2]) / 2) ** 2 - ((a[1] + b[1]) / 2) ** 2) / 2 for a, b in zip(at, at[1:]))


def _cell_polygon(a: np.ndarray, b: np.ndarray, height: float) -> np.ndarray:
    """Corners (x, y) of the cell's cut at `height`, in order."""
    from scipy.spatial import ConvexHull, HalfspaceIntersection

    rows = a[:, :2]
    offsets = b - a[:, 2] * height
    keep = np.linalg.norm(rows, axis=1) > 1e-12
    halfspaces = np.hstack([rows[keep], -offsets[keep, None]])
    from scipy.optimize import linprog

    # An interior point: the centre of the largest disc in the cut (Chebyshev centre).
    norms = np.linalg.norm(rows[keep], axis=1)
    fit = linprog([0, 0, -1], A_ub=np.hstack([rows[keep], norms[:, None]]), b_ub=offsets[keep],
                  bounds=[(None, None), (None, None), (0, None)])
    inside = fit.x[:2]
    corners = HalfspaceIntersection(halfspaces, inside).intersections
    return corners[ConvexHull(corners).vertices]


def add_parser(sub) -> None:
    """`prsc reach ARM_FILE`: build an arm's top-down reachable cell, report its coverage, draw it."""
    parser = sub.add_parser("reach", help="build a URDF/MJCF arm's `reachable by` cell; report its coverage; draw it",
                            description=add_parser.__doc__)
    parser.add_argument("arm", help="the arm's URDF or MJCF file")
    parser.add_argument("-I", "--include", action="append", default=[], metavar="DIR",
                        help="folders where `package://` names are looked up")
    parser.add_argument("--plot", metavar="PNG", help="draw the reach and the cell at the table plane into PNG")


def run(args) -> int:
    """Build (or read from the cache) the arm's cell and print what it keeps."""
    import time

    from prsc.asset_files import describe_asset
    from prsc.constraints.arm_reach import HEIGHTS, arm_reach_cell, reach_cache
    from prsc.errors import PrscError

    if not Path(args.arm).is_file():
        raise PrscError(f"no file {args.arm}")
    asset = describe_asset(args.arm, args.include)
    if not asset.has_joints:
        raise PrscError(f"{args.arm} has no joints: not an arm")
    cached = reach_cache(asset).is_file()
    start = time.process_time()
    try:
        cell = arm_reach_cell(asset)
    except ValueError as error:
        raise PrscError(f"{args.arm}: {error}") from None
    seconds = time.process_time() - start
    print(f"{asset.name}: {len(asset.joints)} joints, tool {asset.tcp}; cell of {len(cell.b)} rows "
          f"({'read from the cache' if cached else f'built in {seconds:.1f} s of CPU'}): {reach_cache(asset)}")
    for height in HEIGHTS:
        reach = _reached_area(list(cell.rays), height)
        corners = _cell_polygon(cell.a, cell.b, height)
        x, y = corners[:, 0], corners[:, 1]
        area = 0.5 * abs(float(np.dot(x, np.roll(y, 1)) - np.dot(y, np.roll(x, 1))))
        far = float(np.max(np.hypot(x, y)))
        print(f"  {height:+.3f} m: the cell keeps {area:.3f} m^2 of the {reach:.3f} m^2 reached top-down over the "
              f"half ahead ({100 * area / reach:.0f} %), farthest point {far:.3f} m from the base")
    if args.plot:
        _plot(cell, args.plot, asset.name)
        print(f"drawn: {args.plot}")
    return 0


def _plot(cell, path: str, name: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(figsize=(6, 6))
    height = min(r[0] for r in cell.rays)
    for h, angle, inner, outer in cell.rays:
        if h == height and inner is not None:
            direction = np.array([math.cos(angle), math.sin(angle)])
            axes.plot(*np.array([inner * direction, outer * direction]).T, color="0.6")
    corners = _cell_polygon(cell.a, cell.b, height)
    axes.fill(corners[:, 0], corners[:, 1], alpha=0.4, label="cell (`reachable by`)")
    axes.plot([0], [0], "k+", label="base")
    axes.set_aspect("equal")
    axes.set_xlabel("x (m, ahead)")
    axes.set_ylabel("y (m)")
    axes.set_title(f"{name}: top-down reach at the base's height\n(grey: reached along each ray)", fontsize=10)
    axes.legend(loc="lower left")
    figure.savefig(path, dpi=100)
    plt.close(figure)


def main() -> None:
    """Regenerate the data file, or report how much of a tray it keeps."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--output", default=str(OUTPUT), help=f"where to write (default {OUTPUT})")
    parser.add_argument("--tray-report", metavar="SPEC", help="instead: the fraction of tr_1 that c1 keeps under r1, vs IK")
    args = parser.parse_args()
    if args.tray_report:
        print(json.dumps(tray_report(args.tray_report, "tr_1", "c1", "r1"), indent=1))
        return
    data = compute()
    atomic_write(args.output, json.dumps(data, indent=1) + "\n")
    print(f"{len(data['cell']['b'])} rows of the cell written to {args.output}")


if __name__ == "__main__":
    main()
