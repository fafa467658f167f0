"""An example controller for any arm (docs/assets.md): the arm's tool visits, top-down, a
point 10 cm above every cube in turn, coming down from 12 cm above it (the height that
`reachable by` certifies with the cube's centre), driven by its own position servos.

    prsc run specs/pybullet_arm/xarm_cubes.prs -I "$PYBULLET_DATA" \\
        --controller prsc.backends.runner.visit:visit -n 5

It knows nothing of a particular robot: the scene's robot object names its asset (the
Panda or a URDF/MJCF file), and the asset's description (prsc.asset_files) gives the
joints, the tool frame and the home pose; the compiled model gives the servos that hold
those joints (a URDF arm gets one per joint from prsc). IK is prsc/arm_ik.py on a scratch
copy of the scene's model. Outcomes: `visited` (the tool came within 1 cm of every point,
pointing down within 0.1 rad), `unreachable` (no top-down pose for a point), `missed` (the
servos did not get the tool there in 4 s). Copy it as the start of a controller of your own.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from prsc.arm_ik import REACH_APPROACH, RESTARTS, ArmFrames, reach_top_down, solve_top_down, turned
from prsc.assets.articulated import robot_model
from prsc.backends.names import with_body_names
from prsc.errors import PrscError

HOVER = 0.10  # m above each cube's centre: a bare flange's link reaches below its frame
# m above that, reached first: the point `reachable by` certifies with the cube's centre
# (REACH_APPROACH above it), so a cube the spec places in reach is visited from there.
APPROACH = REACH_APPROACH - HOVER
TOLERANCE = 0.01  # m
ANGLE = 0.1  # rad
TIMEOUT = 8.0  # simulated s per point


def _robot(scene: dict) -> tuple[dict, object]:
    """The scene's one robot object and its asset."""
    robots = [(o, robot_model(o.get("model"))) for o in with_body_names(scene)["objects"]]
    robots = [(o, r) for o, r in robots if r is not None]
    if len(robots) != 1:
        raise PrscError(f"scene {scene.get('spec', '?')} #{scene.get('index', '?')} does not fit visit: it needs "
                        f"exactly one robot (an object whose model is the Panda or a URDF/MJCF arm), found {len(robots)}")
    return robots[0]


def _cubes(scene: dict) -> list[dict]:
    ancestry = scene.get("classes") or {}
    return [o for o in with_body_names(scene)["objects"]
            if "Cube" in (o.get("class"), *ancestry.get(o.get("class"), []))]


class Visit:
    """Visit a point above every cube with the one robot's tool."""

    outcomes = ("visited", "unreachable", "missed")

    def __call__(self, scene: dict, model: mujoco.MjModel, data: mujoco.MjData) -> dict:
        """One episode: the outcome, why, and the worst distance of the tool from a point."""
        robot, asset = _robot(scene)
        prefix = f"{robot['body']}/"
        tool = (robot.get("properties") or {}).get("tcp") or asset.tcp  # the spec's `with tcp`, else the file's
        arm = ArmFrames.of(model, [prefix + j.name for j in asset.joints if j.name in _arm_joints(model, prefix, asset)],
                           prefix + str(tool))
        servos = _servos(model, arm)
        home = data.qpos[arm.qpos].copy()
        scratch = mujoco.MjData(model)
        # Where the tool heads at home, about the arm's root: each cube is sought from home
        # turned towards it, as `reachable by` sought it (prsc/constraints/arm_reach.py).
        root = data.xpos[model.body(prefix + asset.root).id]
        heading = arm.heading(data, root)
        worst = 0.0
        q = home
        for cube in _cubes(scene):
            goal = np.asarray(cube["position"], float) + np.array([0.0, 0.0, HOVER])
            above = goal + np.array([0.0, 0.0, APPROACH])
            scratch.qpos[:] = data.qpos
            towards = turned(home, arm, heading, math.atan2(goal[1] - root[1], goal[0] - root[0]))
            q, ok = reach_top_down(model, scratch, arm, goal, q, towards, APPROACH, restarts=RESTARTS)
            q_above, ok_above = solve_top_down(model, scratch, arm, above, q)
            if not (ok and ok_above):
                return {"outcome": "unreachable", "reason": f"no top-down pose above {cube['name']}", "worst": worst}
            # Over the cube first, then down onto the point: the path clears what stands around it.
            data.ctrl[servos] = q_above
            _settle(model, data, arm, above)
            data.ctrl[servos] = q
            error = _settle(model, data, arm, goal)
            worst = max(worst, error)
            if error > TOLERANCE:
                return {"outcome": "missed", "reason": f"the tool stayed {error * 1000:.0f} mm from above {cube['name']}",
                        "worst": round(worst, 4)}
        return {"outcome": "visited", "reason": "", "worst": round(worst, 4)}

    @staticmethod
    def check(scene: dict) -> None:
        """Refuse a scene without exactly one robot."""
        _robot(scene)


def _arm_joints(model: mujoco.MjModel, prefix: str, asset) -> set[str]:
    """The asset's joints that a position servo drives (a gripper's mimic finger has none)."""
    driven = set()
    for a in range(model.nu):
        if int(model.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_JOINT):
            name = model.joint(model.actuator_trnid[a, 0]).name
            if name.startswith(prefix):
                driven.add(name[len(prefix):])
    fingers = {j.name for j in asset.joints if j.kind == "prismatic"}
    return driven - fingers


def _servos(model: mujoco.MjModel, arm: ArmFrames) -> np.ndarray:
    """The actuator driving each arm joint, in the arm's joint order."""
    by_joint = {int(model.actuator_trnid[a, 0]): a for a in range(model.nu)
                if int(model.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_JOINT)}
    joints = [int(np.flatnonzero(model.jnt_qposadr == adr)[0]) for adr in arm.qpos]
    return np.array([by_joint[j] for j in joints])


def _settle(model: mujoco.MjModel, data: mujoco.MjData, arm: ArmFrames, goal: np.ndarray) -> float:
    """Step until the tool is at `goal` pointing down (or the timeout); its final distance."""
    end = data.time + TIMEOUT
    error = np.inf
    while data.time < end:
        mujoco.mj_step(model, data, nstep=10)
        position, rotation = arm.tool_pose(data)
        error = float(np.linalg.norm(position - goal))
        if error < TOLERANCE / 2 and np.arccos(min(1.0, -rotation[2, 2])) < ANGLE and np.abs(data.qvel[arm.dofs]).max() < 0.05:
            break
    return error


visit = Visit()
