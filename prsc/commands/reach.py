"""The Panda's top-down reachable set, from its kinematics: the data `reachable by` reads.

`python -m prsc.commands.reach` (`make reach`) regenerates
prsc/constraints/panda_reach.json. The constraint stage reads that file and never
imports MuJoCo; tests/constraints/test_reach.py checks the file against the IK. (A
command, not a backend: it drives the runner's IK and, for the tray report, samples a spec.)

Reachable means what the handover controller needs (prsc/runner/handover.py): with
the gripper pointing down as at home, the tool centre reaches the point 12 cm above it
(the approach, sought from home with restarts as the controller seeks it), then moves
straight down to the point and up 15 cm (the lift) in the controller's 3 cm steps
(ArmIK.solve_line), each IK solved from the previous one, in poses that do not put the arm
into itself. Along each ray from the base (SECTORS directions) and at each height
(HEIGHTS) the longest run of reachable radii is scanned every 5 cm and its ends bisected
to 3 mm.

The reachable set is an annulus about the base, not convex. prsc keeps it as a ring of
exact rows (panda_ring, prsc/constraints/reach_ring.py): an outer convex cell under the
chord of every sector's outer radius, minus a convex hole about the largest inner radii,
over the heights, each bound shrunk by a margin. docs/sampling.md reports how much of the
true reach it keeps (`--coverage`, on the base's plane) and of a tray (`--tray-report SPEC`),
each against the IK on a grid.

`prsc reach ARM_FILE` does the same for an arm from a file (prsc/constraints/arm_reach.py)
and measures the ring against the arm's true top-down reach on a grid.
"""

from __future__ import annotations

import argparse
import json
import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from prsc.files import atomic_write
from prsc.constraints.reach_ring import ReachRing, contains, ring_from_rays, ring_json
from prsc.geometry.rotations import quat_to_matrix

HEIGHTS = (0.0, 0.05, 0.15)  # m above the base: the levels the ring spans
SECTORS = 48
RADII = tuple(round(0.1 + 0.05 * i, 3) for i in range(19))  # the coarse scan, m
REFINE = 4  # bisections of each end of the reachable run (5 cm / 2^4 ~ 3 mm)
MARGIN = 0.001  # m taken off the outer radii (each a radius the IK reached, the chords between them inside)
INNER_MARGIN = 0.01  # m added to the inner radii: near the base the reach is patchy (5 mm kept one point it misses)
COVERAGE_EXTENT = 0.9  # m: the grid of `--coverage` reaches past the farthest radius any ray reaches (0.81)

OUTPUT = Path(__file__).resolve().parent.parent / "constraints" / "panda_reach.json"


class TopDownReach:
    """Whether the Panda's tool centre reaches points top-down (base frame: +y ahead, z up)."""

    def __init__(self) -> None:
        from prsc.assets import panda
        from prsc.runner.grasping import APPROACH_HEIGHT, LIFT_HEIGHT
        from prsc.runner.ik import ArmIK

        self.approach, self.lift = APPROACH_HEIGHT, LIFT_HEIGHT  # the controller's own, read when the arm is built
        self.ik = ArmIK(np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0]))
        self.home = np.array(panda.HOME_QPOS)
        self.down = self.ik.tcp_pose(self.home)[1]

    def reaches(self, point: np.ndarray) -> bool:
        """The approach sought from home as the controller seeks it (ArmIK.solutions_from_home), then
        down to the point and up to the lift in the controller's straight steps (ArmIK.solve_line),
        each from the previous solution, none putting a link into another."""
        point = np.asarray(point, float)
        up = np.array([0.0, 0.0, 1.0])
        approach = point + self.approach * up
        for solution in self.ik.solutions_from_home(approach, self.down):
            if not solution.reached:
                continue
            down = self.ik.solve_line(approach, point, self.down, solution.q, free=True)
            if down[-1].reached and self.ik.solve_line(point, point + self.lift * up, self.down, down[-1].q, free=True)[-1].reached:
                return True
        return False


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


def panda_ring(rays: dict, angles: list[float]) -> ReachRing:
    """The reach kept over the heights: an outer cell minus a hole and a gap
    (prsc/constraints/reach_ring.py); the rays' angles (0: ahead, +y) turn to the ring's (0: +x)
    by +90 deg."""
    per_ray = [[rays[k, j] for k in range(len(HEIGHTS))] for j in range(SECTORS)]
    return ring_from_rays([a + math.pi / 2 for a in angles[:SECTORS]], list(HEIGHTS), per_ray, MARGIN, INNER_MARGIN)


_reach: TopDownReach | None = None  # one per worker process: its IK model is compiled once


def _worker_reach() -> TopDownReach:
    """This process's TopDownReach, built on first use."""
    global _reach
    _reach = _reach or TopDownReach()
    return _reach


def _ray_job(_shared: None, ray: tuple[int, int]) -> tuple[float, float] | None:
    """One ray's reached run: (height index, ray index) (a worker's item)."""
    k, j = ray
    return ray_interval(_worker_reach(), _angles()[j], HEIGHTS[k])


def compute(jobs: int = 1) -> dict:
    """The reachable-set data of the Panda (minutes of IK), its rays scanned by `jobs` processes."""
    from prsc.pipeline.executors import LocalExecutor

    keys = [(k, j) for k in range(len(HEIGHTS)) for j in range(SECTORS)]
    return reach_data(dict(zip(keys, LocalExecutor(jobs).map(_ray_job, None, keys))))


def reach_data(rays: dict[tuple[int, int], tuple[float, float] | None]) -> dict:
    """The data file's content from the rays: (height index, ray index) -> the reached run or None."""
    angles = _angles()
    rays = {**rays, **{(k, SECTORS): rays[k, 0] for k in range(len(HEIGHTS))}}
    ring = panda_ring(rays, angles)
    from prsc.runner.grasping import APPROACH_HEIGHT, LIFT_HEIGHT

    return {
        "robot": "panda",
        "frame": "the arm's base: origin at the bottom centre of the Robot box, +y ahead, +z up",
        "grasp": f"tool centre at the point, {APPROACH_HEIGHT} m and {LIFT_HEIGHT} m above it, gripper pointing down as at home",
        "heights": list(HEIGHTS),
        "angles": angles[:SECTORS],
        "rays": [[k, j, *(rays[k, j] or (None, None))] for k in range(len(HEIGHTS)) for j in range(SECTORS)],
        "margin": MARGIN,
        "inner_margin": INNER_MARGIN,
        "ring": {**ring_json(ring), "heights": [HEIGHTS[0], HEIGHTS[-1]]},
    }


def tray_report(spec: str, tray: str, cube: str, robot: str, step: float = 0.02, jobs: int = 1) -> dict:
    """How much of a tray the cell keeps, against the IK on a grid of cube centres.

    Grid over the cube centres `completely on` the tray allows (scene 0 of seed 0), every
    `step` metres: the fraction in the cell, the fraction the IK reaches, and the
    fraction of the reachable ones the cell keeps (and any cell point the IK misses).
    """
    from prsc.pipeline.executors import LocalExecutor
    from prsc.constraints.reach_rows import reach_ring
    from prsc.sampling import compile_sampler

    scene = compile_sampler(spec).scene(0, 0)
    objects = {o["name"]: o for o in scene["objects"]}
    rot = quat_to_matrix(objects[robot]["quaternion"])
    base = np.asarray(objects[robot]["position"]) - rot[:, 2] * objects[robot]["dimensions"][2] / 2
    centre, dims = np.asarray(objects[tray]["position"]), np.asarray(objects[tray]["dimensions"])
    half_cube = np.asarray(objects[cube]["dimensions"]) / 2
    z = objects[cube]["position"][2]
    ring = reach_ring(objects[robot]["model"])
    xs = np.arange(centre[0] - dims[0] / 2 + half_cube[0], centre[0] + dims[0] / 2 - half_cube[0] + 1e-9, step)
    ys = np.arange(centre[1] - dims[1] / 2 + half_cube[1], centre[1] + dims[1] / 2 - half_cube[1] + 1e-9, step)
    points = np.array([rot.T @ (np.array([x, y, z]) - base) for x in xs for y in ys])
    in_cell = contains(ring, points)
    reached = np.array(LocalExecutor(jobs).map(_reaches_job, None, [tuple(p) for p in points.tolist()]), dtype=bool)
    counts = {"points": len(points), "in_cell": int(in_cell.sum()), "reached": int(reached.sum()),
              "both": int((in_cell & reached).sum())}
    n = counts["points"]
    return {
        **counts, "step": step,
        "cell_fraction_of_tray": counts["in_cell"] / n,
        "reachable_fraction_of_tray": counts["reached"] / n,
        "reachable_kept_by_cell": counts["both"] / max(counts["reached"], 1),
        "cell_points_not_reached": counts["in_cell"] - counts["both"],
    }


def _reaches_job(_shared: None, point: tuple[float, float, float]) -> bool:
    """Whether the Panda's tool reaches one point (a worker's item)."""
    return _worker_reach().reaches(np.array(point))


def panda_edge_check(step: float = 0.01, band: float = 0.02, jobs: int = 1) -> dict:
    """Every point the shipped ring keeps within `band` of its edge, on a `step` grid at the
    lowest and highest height, against the IK: the points where the ring is most likely wrong."""
    from prsc.pipeline.executors import LocalExecutor
    from prsc.constraints.reach_rows import reach_ring

    ring = reach_ring("panda")
    assert ring is not None
    xs = np.arange(-COVERAGE_EXTENT, COVERAGE_EXTENT + step / 2, step)
    offsets = band * np.array([[math.cos(a), math.sin(a), 0.0] for a in np.arange(0, 2 * math.pi, math.pi / 8)])
    report = {"step": step, "band": band}
    for height in (HEIGHTS[0], HEIGHTS[-1]):
        grid = np.array([[x, y, height] for x in xs for y in xs])
        kept = grid[contains(ring, grid)]
        near = kept[[not contains(ring, point + offsets).all() for point in kept]]
        reached = np.array(LocalExecutor(jobs).map(_reaches_job, None, [tuple(p) for p in near.tolist()]), dtype=bool)
        report[f"{height:g} m"] = {"points": len(near), "not_reached": near[~reached].round(3).tolist()}
    return report


def panda_coverage(step: float = 0.03, jobs: int = 1) -> dict:
    """What the shipped ring keeps of the Panda's true top-down reach at its base's height: the
    IK (TopDownReach, as the controller seeks a pose) at every point of a grid about the base."""
    from prsc.pipeline.executors import LocalExecutor
    from prsc.constraints.reach_rows import reach_ring

    ring = reach_ring("panda")
    assert ring is not None
    xs = np.arange(-COVERAGE_EXTENT, COVERAGE_EXTENT + step / 2, step)
    points = np.array([[x, y, 0.0] for x in xs for y in xs if math.hypot(x, y) <= COVERAGE_EXTENT])
    reached = np.array(LocalExecutor(jobs).map(_reaches_job, None, [tuple(p) for p in points.tolist()]), dtype=bool)
    return {"step": step, "points": len(points), **ring_coverage(ring, points, reached)}


def ring_coverage(ring: ReachRing, points: np.ndarray, reached: np.ndarray) -> dict:
    """What a ring keeps of the points a tool reaches: counts, the fraction, and its farthest kept point."""
    kept = contains(ring, points)
    both = int(np.count_nonzero(kept & reached))
    return {
        "reached": int(reached.sum()), "kept_and_reached": both,
        "reached_kept_by_ring": both / max(int(reached.sum()), 1),
        "kept_not_reached": int(kept.sum()) - both,
        "farthest_kept": float(np.max(np.hypot(*points[kept, :2].T))) if kept.any() else 0.0,
    }


def add_parser(sub) -> None:
    """`prsc reach ARM_FILE`: build an arm's top-down reachable cell, report its coverage, draw it."""
    parser = sub.add_parser("reach", help="build a URDF/MJCF arm's `reachable by` cell; report its coverage; draw it",
                            description=add_parser.__doc__)
    parser.add_argument("arm", help="the arm's URDF or MJCF file")
    parser.add_argument("-I", "--include", action="append", default=[], metavar="DIR",
                        help="folders where `package://` names are looked up")
    parser.add_argument("--grid", type=float, default=0.03, metavar="M",
                        help="the step of the grid the true reach is measured on (default 0.03 m)")
    parser.add_argument("--plot", metavar="PNG", help="draw the true reach and the ring at the root's height into PNG")
    parser.add_argument("--tcp", metavar="NAME", help="the tool frame, as a spec's `with tcp` names it (a link, body or "
                        "site; default: a site named tcp, else the last link of the longest chain)")


def run(args) -> int:
    """Build (or read from the cache) the arm's reach and print what it keeps of the true reach."""
    import time

    from prsc.user_assets.asset_files import describe_asset
    from prsc.constraints.arm_reach import HEIGHTS, arm_reach, reach_cache
    from prsc.errors import PrscError

    if not Path(args.arm).is_file():
        raise PrscError(f"no file {args.arm}")
    if not args.grid > 0:
        raise PrscError(f"--grid must be a step > 0 m, not {args.grid}")
    asset = describe_asset(args.arm, args.include)
    if not asset.has_joints:
        raise PrscError(f"{args.arm} has no joints: not an arm")
    if args.tcp is not None:
        if args.tcp not in (*asset.links, *asset.sites):
            raise PrscError(f"--tcp {args.tcp!r} is no link or site of {args.arm}")
        asset = replace(asset, tcp=args.tcp)
    cached = reach_cache(asset).is_file()
    start = time.process_time()
    try:
        ring = arm_reach(asset).ring
    except ValueError as error:
        raise PrscError(f"{args.arm}: {error}") from None
    seconds = time.process_time() - start
    print(f"{asset.name}: {len(asset.joints)} joints, tool {asset.tcp}; reach of {len(ring.b)} rows less a hole of "
          f"{len(ring.hole_b)} ({'read from the cache' if cached else f'built in {seconds:.1f} s of CPU'}): "
          f"{reach_cache(asset)}")
    height = HEIGHTS[0]
    grid = true_reach_grid(asset, height, args.grid)
    kept = ring_coverage(ring, grid.points, grid.reached)
    print(f"  at the root's height, on a {args.grid * 100:g} cm grid with the IK ({grid.seconds:.1f} s): the tool reaches "
          f"{kept['reached']} points top-down; the ring keeps {kept['kept_and_reached']} of them "
          f"({100 * kept['reached_kept_by_ring']:.1f} %) and {kept['kept_not_reached']} points it does not reach; "
          f"farthest kept point {kept['farthest_kept']:.3f} m from the base")
    if args.plot:
        _plot(ring, grid, args.plot, asset.name)
        print(f"drawn: {args.plot}")
    return 0


@dataclass(frozen=True)
class ReachGrid:
    """Points (root frame) on a grid about an arm's base, whether its tool reaches each top-down."""

    points: np.ndarray
    reached: np.ndarray
    seconds: float


def true_reach_grid(asset, height: float, step: float) -> ReachGrid:
    """The arm's true top-down reach at `height` above its root: the IK at every grid point
    within its longest arm's length, from home and from home turned towards the point."""
    import time

    from prsc.constraints.arm_reach import TopDownIK

    ik = TopDownIK(asset)
    extent = ik.span() + step
    xs = np.arange(-extent, extent + step / 2, step)
    points = np.array([[x, y, height] for x in xs for y in xs if math.hypot(x, y) <= extent])
    start = time.process_time()
    reached = np.array([ik.reaches_from_home(p) for p in points], dtype=bool)
    return ReachGrid(points, reached, time.process_time() - start)


def _plot(ring: ReachRing, grid: ReachGrid, path: str, name: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(figsize=(6, 6))
    kept = contains(ring, grid.points)
    for mask, colour, label in ((grid.reached & kept, "tab:green", "reached, kept"),
                                (grid.reached & ~kept, "tab:orange", "reached, not kept"),
                                (~grid.reached & kept, "tab:red", "kept, not reached")):
        if mask.any():
            axes.scatter(grid.points[mask, 0], grid.points[mask, 1], s=4, color=colour, label=label)
    axes.plot([0], [0], "k+", label="base")
    axes.set_aspect("equal")
    axes.set_xlabel("x (m, right)")
    axes.set_ylabel("y (m, ahead)")
    axes.set_title(f"{name}: top-down reach at the root's height\n(the ring `reachable by` keeps, against the IK)",
                   fontsize=10)
    axes.legend(loc="lower left", fontsize=8)
    figure.savefig(path, dpi=100)
    plt.close(figure)


def main() -> None:
    """Regenerate the data file, or report how much of a tray it keeps."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--output", default=str(OUTPUT), help=f"where to write (default {OUTPUT})")
    parser.add_argument("--tray-report", metavar="SPEC", help="instead: the fraction of tr_1 that c1 keeps under r1, vs IK")
    parser.add_argument("--coverage", action="store_true",
                        help="instead: what the ring keeps of the true reach at the base's height (3 cm grid, vs IK)")
    parser.add_argument("--edge-check", action="store_true",
                        help="instead: the IK at every point the ring keeps within 2 cm of its edge (1 cm grid)")
    parser.add_argument("--jobs", type=int, default=1, help="processes running the IK (default 1)")
    args = parser.parse_args()
    if args.edge_check:
        print(json.dumps(panda_edge_check(jobs=args.jobs), indent=1))
        return
    if args.tray_report:
        print(json.dumps(tray_report(args.tray_report, "tr_1", "c1", "r1", jobs=args.jobs), indent=1))
        return
    if args.coverage:
        print(json.dumps(panda_coverage(jobs=args.jobs), indent=1))
        return
    data = compute(args.jobs)
    atomic_write(args.output, json.dumps(data, indent=1) + "\n")
    print(f"{len(data['ring']['b'])} rows of the ring written to {args.output}")


if __name__ == "__main__":
    main()
