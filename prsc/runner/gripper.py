"""A gripper of any arm, found in the compiled model (docs/assets.md, "Controllers for any
arm"): the actuators that drive joints off the chain from the arm's root to its tool (a
joint's own servo, or a fixed tendon over several joints), with the controls that open and
close them. Which end of a control's range closes is computed, not named: forward kinematics
at each end, and the end that brings the fingers nearer the tool's axis closes."""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco
import numpy as np

from prsc.user_assets.arm_ik import ArmFrames
from prsc.runner.arm_scene import chain_joints


@dataclass(frozen=True)
class Gripper:
    """The actuators of a gripper, their open and closed controls, and its closing axis."""

    actuators: np.ndarray  # actuator ids
    opened: np.ndarray  # control per actuator that opens the gripper
    closed: np.ndarray  # and that closes it
    closing: np.ndarray  # horizontal unit vector in the tool's frame along which the fingers close
    fingers: tuple[int, ...] = ()  # the bodies its joints move
    shut: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))  # their centres of mass in the tool's frame when closed

    def opening(self, data: mujoco.MjData, arm: ArmFrames) -> float:
        """How far (m, summed over the fingers, along the closing axis) the fingers stand from
        closed in `data` (after kinematics): what a closed grasp holds between them."""
        position, rotation = arm.tool_pose(data)
        offsets = (data.xipos[list(self.fingers)] - position) @ rotation
        return float(np.abs((offsets - self.shut) @ self.closing).sum())


def gripper_of(model: mujoco.MjModel, prefix: str, arm: ArmFrames, tool: str) -> Gripper | None:
    """The gripper of the arm whose names start with `prefix`, or None when it has none."""
    chain = chain_joints(model, tool)
    scratch = mujoco.MjData(model)
    mujoco.mj_resetData(model, scratch)
    actuators, opened, closed, moves, fingers, shut_at = [], [], [], [], [], []
    for a in range(model.nu):
        joints = _transmission(model, a)
        names = [model.joint(j).name for j, _ in joints]
        if not joints or any(not n.startswith(prefix) or n in chain for n in names):
            continue
        ends = model.actuator_ctrlrange[a] if model.actuator_ctrllimited[a] else _joint_controls(model, a, joints)
        if ends is None:
            continue
        spreads = [_finger_offsets(model, scratch, arm, _joint_values(model, a, joints, c)) for c in ends]
        shut = int(np.argmin([np.linalg.norm(s[:, :2], axis=1).sum() for s in spreads]))
        actuators.append(a)
        closed.append(float(ends[shut]))
        opened.append(float(ends[1 - shut]))
        moves.append(spreads[1 - shut] - spreads[shut])
        fingers += [int(model.jnt_bodyid[j]) for j, _ in joints]
        shut_at.append(spreads[shut])
    if not actuators:
        return None
    motion = np.concatenate(moves)[:, :2]
    main = motion[np.argmax(np.linalg.norm(motion, axis=1))]
    if np.linalg.norm(main) < 1e-6:
        return None  # its joints move nothing across the tool's axis
    axis = main / np.linalg.norm(main)
    return Gripper(np.array(actuators), np.array(opened), np.array(closed), np.array([axis[0], axis[1], 0.0]),
                   tuple(fingers), np.concatenate(shut_at))


def _transmission(model: mujoco.MjModel, a: int) -> list[tuple[int, float]]:
    """(joint id, coefficient) of what actuator `a` moves: its joint, or a fixed tendon's joints."""
    kind = int(model.actuator_trntype[a])
    if kind == int(mujoco.mjtTrn.mjTRN_JOINT):
        return [(int(model.actuator_trnid[a, 0]), 1.0)]
    if kind == int(mujoco.mjtTrn.mjTRN_TENDON):
        tendon = int(model.actuator_trnid[a, 0])
        start, count = model.tendon_adr[tendon], model.tendon_num[tendon]
        wraps = range(start, start + count)
        if all(int(model.wrap_type[w]) == int(mujoco.mjtWrap.mjWRAP_JOINT) for w in wraps):
            return [(int(model.wrap_objid[w]), float(model.wrap_prm[w])) for w in wraps]
    return []


def _joint_controls(model: mujoco.MjModel, a: int, joints: list[tuple[int, float]]) -> np.ndarray | None:
    """The controls that hold a position servo at its one joint's limits (None otherwise)."""
    joint = joints[0][0]
    if len(joints) != 1 or not model.jnt_limited[joint] or model.actuator_biasprm[a, 1] == 0:
        return None
    gain, bias0, bias1 = model.actuator_gainprm[a, 0], model.actuator_biasprm[a, 0], model.actuator_biasprm[a, 1]
    length = model.actuator_gear[a, 0] * model.jnt_range[joint]
    return -(bias0 + bias1 * length) / gain


def _joint_values(model: mujoco.MjModel, a: int, joints: list[tuple[int, float]], control: float) -> dict[int, float]:
    """Where the joints of actuator `a` stand when it holds `control`: a position servo's
    length split over a tendon's joints by their coefficients, a force's end of each range."""
    gain, bias0, bias1 = model.actuator_gainprm[a, 0], model.actuator_biasprm[a, 0], model.actuator_biasprm[a, 1]
    coefs = np.array([c for _, c in joints])
    if bias1 != 0:  # a position servo: gain * control + bias0 + bias1 * length = 0 at rest
        length = -(gain * control + bias0) / bias1 / model.actuator_gear[a, 0]
        values = length * coefs / (coefs @ coefs)
    else:  # a force: each joint pushed to the end of its range the force points to
        values = np.where(np.sign(control * coefs) > 0, np.inf, -np.inf)
    return {j: float(np.clip(v, *model.jnt_range[j])) if model.jnt_limited[j] else float(v)
            for (j, _), v in zip(joints, values)}


def _finger_offsets(model: mujoco.MjModel, data: mujoco.MjData, arm: ArmFrames, values: dict[int, float]) -> np.ndarray:
    """The centres of mass, in the tool's frame, of the bodies of joints `values` set to those
    values (a body's origin stays on a hinge; its mass turns with it)."""
    data.qpos[:] = model.qpos0
    for joint, value in values.items():
        data.qpos[model.jnt_qposadr[joint]] = value if np.isfinite(value) else model.qpos0[model.jnt_qposadr[joint]]
    mujoco.mj_kinematics(model, data)
    position, rotation = arm.tool_pose(data)
    return np.array([rotation.T @ (data.xipos[model.jnt_bodyid[j]] - position) for j in values])
