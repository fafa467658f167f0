"""An example controller for any arm (docs/assets.md): the arm's tool visits, top-down, a
point 10 cm above every cube in turn, coming down from 12 cm above it (the height that
`reachable by` certifies with the cube's centre), driven by its own position servos.

    prsc run specs/pybullet_arm/xarm_cubes.prs -I "$PYBULLET_DATA" \\
        --controller prsc.runner.visit:visit -n 5

It knows nothing of a particular robot: the scene's robot object names its asset (the
Panda or a URDF/MJCF file), and the asset's description (prsc.user_assets.asset_files) gives the
joints, the tool frame and the home pose; the compiled model gives the chain of joints that
moves the tool and the servos that hold them (a URDF arm gets one per joint from prsc). IK
is prsc/user_assets/arm_ik.py on a scratch copy of the scene's model. Outcomes: `visited` (the tool came within 1 cm of every point,
pointing down within 0.1 rad), `unreachable` (no top-down pose for a point), `missed` (the
servos did not get the tool there in 4 s). Copy it as the start of a controller of your own.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from prsc.user_assets.arm_ik import REACH_APPROACH, RESTARTS, reach_top_down, solve_top_down, turned
from prsc.runner.arm_scene import TOLERANCE, SceneArm, scene_cubes, scene_robot, servos, settle

HOVER = 0.10  # m above each cube's centre: a bare flange's link reaches below its frame
# m above that, reached first: the point `reachable by` certifies with the cube's centre
# (REACH_APPROACH above it), so a cube the spec places in reach is visited from there.
APPROACH = REACH_APPROACH - HOVER


class Visit:
    """Visit a point above every cube with the one robot's tool."""

    outcomes = ("visited", "unreachable", "missed")

    def __call__(self, scene: dict, model: mujoco.MjModel, data: mujoco.MjData) -> dict:
        """One episode: the outcome, why, and the worst distance of the tool from a point."""
        scene_arm = SceneArm.of(scene, model, "visit")
        arm = scene_arm.frames
        drive = servos(model, arm)
        home = data.qpos[arm.qpos].copy()
        scratch = mujoco.MjData(model)
        root, heading = scene_arm.root_and_heading(model, data)
        worst = 0.0
        q = home
        for cube in scene_cubes(scene):
            goal = np.asarray(cube["position"], float) + np.array([0.0, 0.0, HOVER])
            above = goal + np.array([0.0, 0.0, APPROACH])
            scratch.qpos[:] = data.qpos
            towards = turned(home, arm, heading, math.atan2(goal[1] - root[1], goal[0] - root[0]))
            q, ok = reach_top_down(model, scratch, arm, goal, q, towards, APPROACH, restarts=RESTARTS)
            q_above, ok_above = solve_top_down(model, scratch, arm, above, q)
            if not (ok and ok_above):
                return {"outcome": "unreachable", "reason": f"no top-down pose above {cube['name']}", "worst": worst}
            # Over the cube first, then down onto the point: the path clears what stands around it.
            data.ctrl[drive] = q_above
            settle(model, data, arm, above)
            data.ctrl[drive] = q
            error = settle(model, data, arm, goal)
            worst = max(worst, error)
            if error > TOLERANCE:
                return {"outcome": "missed", "reason": f"the tool stayed {error * 1000:.0f} mm from above {cube['name']}",
                        "worst": round(worst, 4)}
        return {"outcome": "visited", "reason": "", "worst": round(worst, 4)}

    @staticmethod
    def check(scene: dict) -> None:
        """Refuse a scene without exactly one robot."""
        scene_robot(scene, "visit")


visit = Visit()
