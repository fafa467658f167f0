"""`reachable by R` for an arm from a file (docs/assets.md): one convex cell of the points
its tool reaches top-down, computed from the arm's own kinematics and cached by the file's
content in the build folder (`$PRSC_BUILD_DIR/reach/<key>.json`), so a second compile
costs nothing.

Top-down means the tool frame's +z (the flange normal of a URDF arm's last link, or the
`tcp` site's z) points straight down, any yaw. A point counts as reached when a damped
least-squares IK on the arm's MuJoCo model brings the tool there within 2 mm and 0.02 rad,
and also 12 cm above it (the approach). Along each ray from the base (every 15 degrees over
the half ahead, +x of the file's root frame, the ROS convention) and at each height
(HEIGHTS above the root's origin) the reachable radii are scanned every 5 cm and the
outer end bisected to 3 mm. The cell is the half-space ahead of the base beyond the
largest inner radius, cut by the chord of every sector's outer radius, each bound
shrunk by a margin: the same construction as the Panda's (prsc/commands/reach.py).
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from prsc.arm_ik import ArmFrames, reach_top_down
from prsc.asset_files import ArticulatedAsset, asset_spec, build_root
from prsc.files import atomic_write

RECIPE_VERSION = "3"  # the IK (prsc/arm_ik.py), the construction below and the model it reads (asset_spec)
APPROACH = 0.12  # m above the point the tool must also reach
HEIGHTS = (0.0, 0.075, 0.15)  # m above the root origin: the levels the cell spans
SECTORS = 12  # rays over the half ahead: every 15 degrees from -90 to +90
RADII = tuple(round(0.05 + 0.05 * i, 3) for i in range(30))  # the coarse scan, m
REFINE = 4  # bisections of the outer end (5 cm / 2^4 ~ 3 mm)
MARGIN = 0.01  # m taken off the outer radii
INNER_MARGIN = 0.03  # m added to the inner radius


@dataclass(frozen=True)
class ReachCell:
    """The cell's rows A p <= b in the arm's root frame, and how it was measured."""

    a: np.ndarray
    b: np.ndarray
    rays: tuple[tuple[float, float, float | None, float | None], ...]  # (height, angle, inner, outer)


class TopDownIK:
    """The arm alone (its file's model), asked whether its tool reaches points top-down (root frame)."""

    def __init__(self, asset: ArticulatedAsset) -> None:
        import mujoco

        self.model = asset_spec(asset.source).compile()
        self.data = mujoco.MjData(self.model)
        self.arm = ArmFrames.of(self.model, [j.name for j in asset.joints], str(asset.tcp))
        self.home = np.array([j.home for j in asset.joints])
        mujoco.mj_kinematics(self.model, self.data)
        self.root = self.data.xpos[self.model.body(asset.root).id].copy()

    def reaches(self, point: np.ndarray, seed: np.ndarray) -> tuple[np.ndarray, bool]:
        """Whether the tool reaches the point (root frame) and the approach above it, top-down."""
        return reach_top_down(self.model, self.data, self.arm, point + self.root, seed, self.home, APPROACH)


def _ray_point(angle: float, radius: float, height: float) -> np.ndarray:
    """The point at `radius` along the ray `angle` (0: ahead, +x; positive towards +y)."""
    return np.array([radius * math.cos(angle), radius * math.sin(angle), height])


def _ray(ik: TopDownIK, angle: float, height: float) -> tuple[float, float] | None:
    """The first run of reachable radii along a ray, its outer end refined; None if none."""
    q = ik.home
    run: list[float] = []
    last_q = q
    for radius in RADII:
        q_new, ok = ik.reaches(_ray_point(angle, radius, height), q)
        if ok:
            run.append(radius)
            q = last_q = q_new
        elif run:
            break
    if not run:
        return None
    inside, outside = run[-1], run[-1] + (RADII[1] - RADII[0])
    for _ in range(REFINE):
        mid = (inside + outside) / 2
        q_mid, ok = ik.reaches(_ray_point(angle, mid, height), last_q)
        if ok:
            inside, last_q = mid, q_mid
        else:
            outside = mid
    return run[0], inside


def compute_cell(asset: ArticulatedAsset) -> ReachCell:
    """The arm's convex top-down cell (a few seconds of IK)."""
    ik = TopDownIK(asset)
    angles = [-math.pi / 2 + math.pi * j / SECTORS for j in range(SECTORS + 1)]
    rays = {(k, j): _ray(ik, angle, height) for k, height in enumerate(HEIGHTS) for j, angle in enumerate(angles)}
    if any(r is None for r in rays.values()):
        missing = sorted({round(math.degrees(angles[j])) for (k, j), r in rays.items() if r is None})
        raise ValueError(f"the tool reaches nothing top-down along the rays at {missing} degrees")
    inner = max(r[0] for r in rays.values()) + INNER_MARGIN  # type: ignore[index]
    rows, offsets = [[-1.0, 0.0, 0.0]], [-inner]
    for j in range(SECTORS):
        r_out = min(rays[k, jj][1] for k in range(len(HEIGHTS)) for jj in (j, j + 1)) - MARGIN  # type: ignore[index]
        if r_out <= inner:
            raise ValueError("the arm's top-down reach is too thin ahead of its base for one convex cell")
        half = (angles[j + 1] - angles[j]) / 2
        rows.append(list(_ray_point(angles[j] + half, 1.0, 0.0)))
        offsets.append(r_out * math.cos(half))
    rows += [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]
    offsets += [HEIGHTS[-1], -HEIGHTS[0]]
    table = tuple((HEIGHTS[k], angles[j], *(rays[k, j] or (None, None))) for k, j in sorted(rays))
    return ReachCell(np.array(rows), np.array(offsets), table)  # type: ignore[arg-type]


def reach_cache(asset: ArticulatedAsset) -> Path:
    """Where an arm's cell is cached: keyed by its file's content and this recipe."""
    return build_root() / "reach" / f"{asset.key}-v{RECIPE_VERSION}.json"


def arm_reach_cell(asset: ArticulatedAsset) -> ReachCell:
    """The arm's cell, computed on first use and read from the cache after."""
    path = reach_cache(asset)
    if path.is_file():
        data = json.loads(path.read_text(encoding="utf-8"))
        return ReachCell(np.array(data["A"]), np.array(data["b"]), tuple(tuple(r) for r in data["rays"]))
    cell = compute_cell(asset)
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(path, json.dumps({
        "asset": os.path.basename(asset.source), "sha256": asset.digest,
        "frame": "the arm's root frame: origin at the root body, +x ahead, +z up",
        "A": cell.a.tolist(), "b": cell.b.tolist(), "rays": [list(r) for r in cell.rays],
    }, indent=1) + "\n")
    return cell
