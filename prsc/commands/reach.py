"""`prsc reach ARM`: an arm's `reachable by` ring (prsc/constraints/arm_reach.py, the one
builder for every arm: a URDF or MJCF file, or a library arm by name), measured against the
arm's true top-down reach on a grid (`ring_coverage`), and with `--edge-check` against the IK at
every point it keeps near its edge, where it is most likely wrong (docs/assets.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from prsc.constraints.reach_ring import ReachRing, contains

EDGE_STEP = 0.01  # m: the grid of `--edge-check`
EDGE_BAND = 0.02  # m: a kept point counts as near the edge when one this far from it is not kept


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
    parser.add_argument("arm", help="the arm's URDF or MJCF file, or the name of a library arm (prsc/library/NAME.json)")
    parser.add_argument("-I", "--include", action="append", default=[], metavar="DIR",
                        help="folders where `package://` names are looked up")
    parser.add_argument("--grid", type=float, default=0.03, metavar="M",
                        help="the step of the grid the true reach is measured on (default 0.03 m)")
    parser.add_argument("--plot", metavar="PNG", help="draw the true reach and the ring at the root's height into PNG")
    parser.add_argument("--edge-check", action="store_true",
                        help=f"also the IK at every point the ring keeps within {EDGE_BAND * 100:g} cm of its edge "
                             f"({EDGE_STEP * 100:g} cm grid, lowest and highest heights): points kept but not reached")
    parser.add_argument("--tcp", metavar="NAME", help="the tool frame, as a spec's `with tcp` names it (a link, body or "
                        "site; default: a site named tcp, else the last link of the longest chain)")


def run(args) -> int:
    """Build (or read from the cache) the arm's reach and print what it keeps of the true reach."""
    import time

    from prsc.user_assets.asset_files import describe_asset, model_asset
    from prsc.user_assets.asset_fitting import library_arm
    from prsc.constraints.arm_reach import HEIGHTS, arm_reach, reach_cache
    from prsc.errors import PrscError

    if library_arm(args.arm) is None and not Path(args.arm).is_file():
        raise PrscError(f"no file {args.arm} (nor a library arm of that name)")
    if not args.grid > 0:
        raise PrscError(f"--grid must be a step > 0 m, not {args.grid}")
    asset = model_asset(args.arm) if library_arm(args.arm) is not None else describe_asset(args.arm, args.include)
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
    if args.edge_check:
        for height, near, missed in edge_check(asset, ring, (HEIGHTS[0], HEIGHTS[-1])):
            print(f"  edge check {height:g} m above the root: {near} points within {EDGE_BAND * 100:g} cm of the edge, "
                  f"{len(missed)} not reached" + (f": {missed}" if missed else ""))
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


def edge_check(asset, ring: ReachRing, heights) -> list[tuple[float, int, list]]:
    """At each height, the points the ring keeps within EDGE_BAND of its edge (an EDGE_STEP grid)
    and those of them the IK does not reach top-down from home turned towards them."""
    from prsc.constraints.arm_reach import TopDownIK

    ik = TopDownIK(asset)
    extent = ik.span() + EDGE_STEP
    xs = np.arange(-extent, extent + EDGE_STEP / 2, EDGE_STEP)
    around = EDGE_BAND * np.array([[math.cos(a), math.sin(a), 0.0] for a in np.arange(0, 2 * math.pi, math.pi / 8)])
    report = []
    for height in heights:
        grid = np.array([[x, y, height] for x in xs for y in xs])
        kept = grid[contains(ring, grid)]
        near = [point for point in kept if not contains(ring, point + around).all()]
        missed = [point.round(3).tolist() for point in near if not ik.reaches_from_home(point)]
        report.append((float(height), len(near), missed))
    return report


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
