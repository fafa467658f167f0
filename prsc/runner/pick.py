"""An example pick for any arm with a gripper (docs/assets.md, "Controllers for any arm"):
each cube in turn is grasped top-down across two faces, lifted 12 cm, set back down where
it was and let go, under the arm's own servos.

    prsc run specs/pybullet_arm/franka_pick.prs -I "$PYBULLET_DATA" \\
        --controller prsc.runner.pick:pick -n 5

It knows no robot by name. The arm is the chain of joints that moves the tool
(prsc/runner/arm_scene.py); the gripper is whatever the model's actuators drive off
that chain, with its closing end and closing axis computed by forward kinematics
(prsc/runner/gripper.py). The tool's closing axis is turned across the cube's faces
(`facing` in prsc/user_assets/arm_ik.py), and the tool goes down and up in a straight line of
waypoints. Outcomes: `picked` (every cube lifted by at least 6 cm and put back),
`unreachable` (no top-down grasp of a cube), `missed` (the servos did not bring the tool
to a waypoint), `dropped` (the cube did not come up with the gripper).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from prsc.user_assets.arm_ik import REACH_APPROACH, ArmFrames, random_starts, reach_top_down, solve_top_down, turned
from prsc.runner.arm_scene import TOLERANCE, SceneArm, ramp, scene_cubes, scene_robot, servos, settle
from prsc.runner.gripper import Gripper, gripper_of
from prsc.errors import PrscError

LIFT = REACH_APPROACH  # m: the cube goes up to the point `reachable by` certifies above it
LIFTED = 0.5 * LIFT  # m the cube must rise with the gripper to count as lifted
GRIP_TIME = 1.0  # simulated s for the fingers to open or close
GRASP_RESTARTS = 16  # starts drawn within the joint limits where home turned towards a cube fails:
# with prsc.user_assets.arm_ik.RESTARTS (4), 4 of 20 Franka episodes found no grasp of a cube 0.43-0.48 m away
CLEARANCE = 0.15  # m above the first waypoint where the arm arrives from its starting pose: the joint-space
# line from a Franka standing straight up to a pose 12 cm above a cube near its base swept the fingers
# through that cube (3 cm) in 2 of 20 episodes; from higher up it descends in the straight steps below
DESCENT_STEP = 0.03  # m between the waypoints down onto a cube: a servo's path between two
# poses is a line in joint space, which near the edge of the reach swings the fingers into the cube


class Pick:
    """Pick every cube top-down with the one robot's gripper and put it back."""

    outcomes = ("picked", "unreachable", "missed", "dropped")

    def __call__(self, scene: dict, model: mujoco.MjModel, data: mujoco.MjData) -> dict:
        """One episode: the outcome, why, and how high the last cube was lifted."""
        scene_arm = SceneArm.of(scene, model, "pick")
        arm = scene_arm.frames
        gripper = _gripper(scene_arm, model)
        drive = servos(model, arm)
        home = data.qpos[arm.qpos].copy()
        root, heading = scene_arm.root_and_heading(model, data)
        scratch = mujoco.MjData(model)
        _grip(model, data, gripper, gripper.opened)
        rise = 0.0
        for cube in scene_cubes(scene):
            body = model.body(cube["body"]).id
            centre = data.xpos[body].copy()
            scratch.qpos[:] = data.qpos
            towards = turned(home, arm, heading, math.atan2(centre[1] - root[1], centre[0] - root[0]))
            points = _heights(centre)
            plan = _grasp_plan(model, scratch, arm, gripper, points, data.xmat[body].reshape(3, 3), towards)
            if plan is None:
                return {"outcome": "unreachable", "reason": f"no top-down grasp of {cube['name']}", "lift": rise}
            down = list(zip(plan, points))
            up = down[::-1]
            clear = points[0] + np.array([0.0, 0.0, CLEARANCE])
            q_clear, ok = solve_top_down(model, scratch, arm, clear, plan[0])
            for q, point in ([(q_clear, clear)] if ok else []) + down:
                ramp(model, data, drive, q)
                error = settle(model, data, arm, point)
                if error > TOLERANCE:
                    return {"outcome": "missed", "reason": f"the tool stayed {error * 1000:.0f} mm from its waypoint "
                            f"at {cube['name']}", "lift": rise}
            _grip(model, data, gripper, gripper.closed)
            _follow(model, data, arm, drive, up)
            rise = round(float(data.xpos[body][2] - centre[2]), 4)
            if rise < LIFTED:
                return {"outcome": "dropped", "reason": f"{cube['name']} rose {rise * 100:.1f} cm with the gripper",
                        "lift": rise}
            _follow(model, data, arm, drive, down)
            _grip(model, data, gripper, gripper.opened)
            _follow(model, data, arm, drive, up)
            # Back to the pose the episode started in: a joint-space line from one cube's pose
            # to the next can sweep the arm through the table (a Franka stuck 84 cm short).
            ramp(model, data, drive, home)
        return {"outcome": "picked", "reason": "", "lift": rise}

    @staticmethod
    def check(scene: dict) -> None:
        """Refuse a scene without exactly one robot (its gripper is sought in the compiled model)."""
        scene_robot(scene, "pick")


def _gripper(scene_arm: SceneArm, model: mujoco.MjModel) -> Gripper:
    gripper = gripper_of(model, scene_arm.prefix, scene_arm.frames, scene_arm.tool)
    if gripper is None:
        raise PrscError(f"{scene_arm.robot['name']} has no gripper for pick: no actuator drives a joint off "
                        f"the chain that moves its tool {scene_arm.tool}")
    return gripper


def _heights(centre: np.ndarray) -> list[np.ndarray]:
    """The tool's waypoints down onto a cube's centre: LIFT above it, then every DESCENT_STEP."""
    return [centre + np.array([0.0, 0.0, h]) for h in np.arange(LIFT, -1e-9, -DESCENT_STEP)]


def _grasp_plan(model, scratch: mujoco.MjData, arm: ArmFrames, gripper: Gripper, points: list[np.ndarray],
                rotation: np.ndarray, towards: np.ndarray) -> list[np.ndarray] | None:
    """The joints at each of `points` (`_heights` of the cube's centre, the last) with the closing
    axis across two of the cube's faces, each solved from the one below it (so the servos follow
    a straight line), or None. Sought from home turned towards the cube, then from
    GRASP_RESTARTS starts within the limits."""
    for start in [towards, *random_starts(arm, towards, GRASP_RESTARTS)]:
        q, ok = reach_top_down(model, scratch, arm, points[-1], start, start, LIFT)
        if ok:
            plan = _facing_plan(model, scratch, arm, gripper, points, rotation, q)
            if plan is not None:
                return plan
    return None


def _facing_plan(model, scratch: mujoco.MjData, arm: ArmFrames, gripper: Gripper, points: list[np.ndarray],
                 rotation: np.ndarray, q: np.ndarray) -> list[np.ndarray] | None:
    """`_grasp_plan`'s waypoints from a top-down pose `q` at the cube (the tool at any yaw), or None."""
    # The four side faces' normals, nearest the closing axis as it stands first: the least turn
    # of the wrist (a gripper closes alike along a normal and its opposite, a wrist's limits do not).
    scratch.qpos[arm.qpos] = q
    mujoco.mj_kinematics(model, scratch)
    axis = arm.tool_pose(scratch)[1] @ gripper.closing
    normals = [sign * rotation[:, c] * np.array([1.0, 1.0, 0.0]) for c in (0, 1) for sign in (1.0, -1.0)]
    normals = sorted((n / np.linalg.norm(n) for n in normals if np.linalg.norm(n) > 1e-6), key=lambda n: -(n @ axis))
    for normal in normals:
        facing = (gripper.closing, normal)
        step, ok = solve_top_down(model, scratch, arm, points[-1], q, facing=facing)
        plan = [step]
        for point in points[-2::-1]:
            if not ok:
                break
            step, ok = solve_top_down(model, scratch, arm, point, plan[-1], facing=facing)
            plan.append(step)
        if ok:
            return plan[::-1]
    return None


def _follow(model, data: mujoco.MjData, arm: ArmFrames, drive: np.ndarray, path: list) -> None:
    """Drive the arm through (joints, tool point) waypoints `path`, each until it arrives or times out."""
    for q, point in path:
        ramp(model, data, drive, q)
        settle(model, data, arm, point)


def _grip(model: mujoco.MjModel, data: mujoco.MjData, gripper: Gripper, controls: np.ndarray) -> None:
    """Set the gripper's controls and let the fingers move for GRIP_TIME, the arm held."""
    data.ctrl[gripper.actuators] = controls
    end = data.time + GRIP_TIME
    while data.time < end:
        mujoco.mj_step(model, data, nstep=10)


pick = Pick()
