"""What a controller for any arm reads from a scene and its compiled model (docs/assets.md,
"Controllers for any arm"): the one robot object and its asset, the cubes, the arm's own
joints (those on the chain from the root to the tool), the servos that drive them, and a
wait until the tool stands at a point top-down."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from prsc.user_assets.arm_ik import ArmFrames
from prsc.user_assets.joint_servos import is_position_servo
from prsc.assets.articulated import robot_model
from prsc.backends.names import with_body_names
from prsc.errors import PrscError

TOLERANCE = 0.01  # m from its goal where the tool has arrived
ANGLE = 0.1  # rad from straight down
TIMEOUT = 8.0  # simulated s the servos get to bring the tool there
JOINT_SPEED = 1.0  # rad/s (m/s) at which `ramp` moves the servos' targets: a step in the targets
# of stiff servos overshoots (an arm's tool fell 14 cm below a point it was sent to)


@dataclass(frozen=True)
class SceneArm:
    """The scene's robot in its compiled model: object, asset, name prefix and arm frames."""

    robot: dict  # the scene object
    asset: object  # its prsc.assets.articulated.RobotModel
    prefix: str  # "<object>/" before every name of the asset in the model
    frames: ArmFrames  # the chain's joints and the tool
    tool: str  # the tool frame's name in the model

    @staticmethod
    def of(scene: dict, model: mujoco.MjModel, controller: str) -> "SceneArm":
        """The scene's one robot in `model`; a PrscError naming `controller` when there is not exactly one."""
        return SceneArm.of_robot(*scene_robot(scene, controller), model)

    @staticmethod
    def of_robot(robot: dict, asset: object, model: mujoco.MjModel) -> "SceneArm":
        """A robot object (with its `body`) and its asset in `model`."""
        prefix = f"{robot['body']}/"
        tool = prefix + str((robot.get("properties") or {}).get("tcp") or asset.tcp)  # the spec's `with tcp`, else the file's
        moving = chain_joints(model, tool) & driven_joints(model)
        joints = [prefix + j.name for j in asset.joints if prefix + j.name in moving]
        return SceneArm(robot, asset, prefix, ArmFrames.of(model, joints, tool), tool)

    def root_and_heading(self, model: mujoco.MjModel, data: mujoco.MjData) -> tuple[np.ndarray, float]:
        """Where the arm's root stands in `data`, and the azimuth of its tool about it: each cube
        is sought from home turned towards it, as `reachable by` sought it (constraints/arm_reach.py)."""
        root = data.xpos[model.body(self.prefix + self.asset.root).id].copy()
        return root, self.frames.heading(data, root)


def scene_robot(scene: dict, controller: str) -> tuple[dict, object]:
    """The scene's one robot object and its asset."""
    robots = [(o, robot_model(o.get("model"))) for o in with_body_names(scene)["objects"]]
    robots = [(o, r) for o, r in robots if r is not None]
    if len(robots) != 1:
        raise PrscError(f"scene {scene.get('spec', '?')} #{scene.get('index', '?')} does not fit {controller}: it needs "
                        f"exactly one robot (an object whose model is a URDF/MJCF arm, the library's too), found {len(robots)}")
    return robots[0]


def scene_cubes(scene: dict) -> list[dict]:
    """The scene's objects of class Cube or a subclass, with their body names."""
    ancestry = scene.get("classes") or {}
    return [o for o in with_body_names(scene)["objects"]
            if "Cube" in (o.get("class"), *ancestry.get(o.get("class"), []))]


def tool_body(model: mujoco.MjModel, tool: str) -> int:
    """The body that carries the tool frame `tool` (a site, else a body)."""
    try:
        return int(model.site_bodyid[model.site(tool).id])
    except KeyError:
        return model.body(tool).id


def chain_joints(model: mujoco.MjModel, tool: str) -> set[str]:
    """The names of the joints that move the tool: those of its body and every body above it."""
    body, names = tool_body(model, tool), set()
    while body > 0:
        start, count = model.body_jntadr[body], model.body_jntnum[body]
        names.update(model.joint(j).name for j in range(start, start + count))
        body = int(model.body_parentid[body])
    return names


def _joint_actuators(model: mujoco.MjModel) -> dict[int, int]:
    """The actuator that drives each joint directly, by joint id: its position servo where it has
    one beside a torque motor (prsc's, next to robosuite's motors), as controllers send positions."""
    found: dict[int, int] = {}
    for a in range(model.nu):
        if int(model.actuator_trntype[a]) != int(mujoco.mjtTrn.mjTRN_JOINT):
            continue
        joint = int(model.actuator_trnid[a, 0])
        if joint not in found or is_position_servo(model, a):
            found[joint] = a
    return found


def driven_joints(model: mujoco.MjModel) -> set[str]:
    """The names of the joints an actuator drives directly."""
    return {model.joint(j).name for j in _joint_actuators(model)}


def servos(model: mujoco.MjModel, arm: ArmFrames) -> np.ndarray:
    """The actuator driving each arm joint, in the arm's joint order."""
    by_joint = _joint_actuators(model)
    joints = [int(np.flatnonzero(model.jnt_qposadr == adr)[0]) for adr in arm.qpos]
    return np.array([by_joint[j] for j in joints])


def settle(model: mujoco.MjModel, data: mujoco.MjData, arm: ArmFrames, goal: np.ndarray) -> float:
    """Step until the tool is at `goal` pointing down and still (or TIMEOUT); its final distance."""
    end = data.time + TIMEOUT
    error = np.inf
    while data.time < end:
        mujoco.mj_step(model, data, nstep=10)
        position, rotation = arm.tool_pose(data)
        error = float(np.linalg.norm(position - goal))
        if error < TOLERANCE / 2 and np.arccos(min(1.0, -rotation[2, 2])) < ANGLE and np.abs(data.qvel[arm.dofs]).max() < 0.05:
            break
    return error


def ramp(model: mujoco.MjModel, data: mujoco.MjData, drive: np.ndarray, q: np.ndarray) -> None:
    """Move the targets of servos `drive` from their current values to `q` at JOINT_SPEED, stepping."""
    start = data.ctrl[drive].copy()
    duration = float(np.abs(q - start).max()) / JOINT_SPEED
    end = data.time + duration
    while data.time < end:
        mujoco.mj_step(model, data, nstep=10)
        data.ctrl[drive] = start + (q - start) * min(1.0, 1.0 - (end - data.time) / duration)
    data.ctrl[drive] = q
