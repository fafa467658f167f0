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

from prsc.asset_files import ArticulatedAsset, asset_spec, build_root
from prsc.files import atomic_write

RECIPE_VERSION = "1"
APPROACH = 0.12  # m above the point the tool must also reach
HEIGHTS = (0.0, 0.075, 0.15)  # m above the root origin: the levels the cell spans
SECTORS = 12  # rays over the half ahead: every 15 degrees from -90 to +90
RADII = tuple(round(0.05 + 0.05 * i, 3) for i in range(30))  # the coarse scan, m
REFINE = 4  # bisections of the outer end (5 cm / 2^4 ~ 3 mm)
MARGIN = 0.01  # m taken off the outer radii
INNER_MARGIN = 0.03  # m added to the inner radius
POSITION_TOLERANCE = 0.002  # m
ANGLE_TOLERANCE = 0.02  # rad


@dataclass(frozen=True)
class ReachCell:
    """The cell's rows A p <= b in the arm's root frame, and how it was measured."""

    a: np.ndarray
    b: np.ndarray
    rays: tuple[tuple[float, float, float | None, float | None], ...]  # (height, angle, inner, outer)


class TopDownIK:
    """Damped least-squares IK of an arm's tool to a position with its +z pointing down."""

    def __init__(self, asset: ArticulatedAsset) -> None:
        import mujoco

        spec = asset_spec(asset.source)
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        self.site = asset.tcp if asset.tcp in asset.sites else None
        self.body = None if self.site else self.model.body(asset.tcp).id
        if self.site:
            self.site = self.model.site(self.site).id
        self.lower = np.where(self.model.jnt_limited, self.model.jnt_range[:, 0], -np.inf)
        self.upper = np.where(self.model.jnt_limited, self.model.jnt_range[:, 1], np.inf)
        self.home = np.array([j.home for j in asset.joints])
        root = self.model.body(asset.root).id
        mujoco.mj_kinematics(self.model, self.data)
        self.root = self.data.xpos[root].copy()

    def _tool(self):
        if self.site is not None:
            return self.data.site_xpos[self.site], self.data.site_xmat[self.site].reshape(3, 3)
        return self.data.xpos[self.body], self.data.xmat[self.body].reshape(3, 3)

    def solve(self, target: np.ndarray, q: np.ndarray, iterations: int = 80) -> tuple[np.ndarray, bool]:
        """(joint values, reached) for the tool at `target` (root frame) pointing down, from `q`."""
        import mujoco

        model, data = self.model, self.data
        goal = np.asarray(target, float) + self.root
        jacp, jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
        down = np.array([0.0, 0.0, -1.0])
        q = np.clip(np.array(q, float), self.lower, self.upper)
        for _ in range(iterations):
            data.qpos[:] = q
            mujoco.mj_kinematics(model, data)
            mujoco.mj_comPos(model, data)
            position, rotation = self._tool()
            error_p = goal - position
            axis = rotation[:, 2]
            error_r = np.cross(axis, down)
            if np.linalg.norm(error_p) < POSITION_TOLERANCE and math.acos(min(1.0, -axis[2])) < ANGLE_TOLERANCE:
                return q, True
            if self.site is not None:
                mujoco.mj_jacSite(model, data, jacp, jacr, self.site)
            else:
                mujoco.mj_jacBody(model, data, jacp, jacr, self.body)
            # Turning about the vertical leaves a top-down grasp top-down: drop it from the task.
            horizontal = np.eye(3) - np.outer(down, down)
            jac = np.vstack([jacp, horizontal @ jacr])
            error = np.concatenate([error_p, horizontal @ error_r])
            step = jac.T @ np.linalg.solve(jac @ jac.T + 1e-4 * np.eye(6), error)
            q = np.clip(q + step, self.lower, self.upper)
        return q, False

    def reaches(self, point: np.ndarray, seed: np.ndarray) -> tuple[np.ndarray, bool]:
        """Whether the tool reaches the point and the approach above it, top-down."""
        above = point + np.array([0.0, 0.0, APPROACH])
        # Straight-up homes are singular for a top-down pose: bent starts get past that.
        bend = np.where(np.arange(len(self.home)) % 2, 0.5, -0.5)
        for start in (seed, self.home, self.home + bend, self.home - bend):
            q, ok = self.solve(above, start)
            if ok:
                q, ok = self.solve(point, q)
                if ok:
                    return q, True
        return seed, False


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
