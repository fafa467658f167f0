"""Inverse kinematics of one Panda with mink, on an arm-only model placed like the scene's arm."""

from __future__ import annotations

from dataclasses import dataclass

import mink
import mujoco
import numpy as np

from prsc.assets import panda

# Reached means: tool centre within 5 mm and 3 degrees of the target.
POSITION_TOLERANCE = 0.005
ORIENTATION_TOLERANCE = np.radians(3.0)
_MAX_ITERATIONS = 300
_DT = 0.05


@dataclass(frozen=True)
class IKSolution:
    """Arm joint angles for a target, and how far the tool centre stays from the target."""

    q: np.ndarray
    position_error: float
    orientation_error: float

    @property
    def reached(self) -> bool:
        """Whether the target was reached within tolerance."""
        return self.position_error <= POSITION_TOLERANCE and self.orientation_error <= ORIENTATION_TOLERANCE


class ArmIK:
    """Solves tool-centre poses for one arm whose base sits at a given world pose."""

    def __init__(self, base_pos: np.ndarray, base_quat: np.ndarray):
        spec = panda.panda_mjcf_spec()
        # Kinematics only: no contacts needed.
        spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
        self.model = spec.compile()
        self._base = self.model.body(panda.BASE_BODY).id
        self.place(base_pos, base_quat)
        self._qadr = np.array([self.model.jnt_qposadr[self.model.joint(j).id] for j in panda.ARM_JOINTS])
        self.configuration = mink.Configuration(self.model)
        self.tcp_task = mink.FrameTask(panda.TCP_SITE, "site", position_cost=1.0, orientation_cost=1.0, lm_damping=1e-3)
        self.posture_task = mink.PostureTask(self.model, cost=1e-3)
        self.limits = [mink.ConfigurationLimit(self.model)]
        self.home = self.full_q(np.array(panda.HOME_QPOS))
        self.posture_task.set_target(self.home)

    def place(self, base_pos: np.ndarray, base_quat: np.ndarray) -> None:
        """Put the arm's base at a world pose (the model is re-posed, not compiled again)."""
        quat = np.asarray(base_quat, float)
        self.model.body_pos[self._base] = np.asarray(base_pos, float)
        self.model.body_quat[self._base] = quat / np.linalg.norm(quat)

    def full_q(self, arm_q: np.ndarray) -> np.ndarray:
        """The arm-only model's qpos for arm joint angles (fingers open)."""
        q = self.model.qpos0.copy()
        q[self._qadr] = arm_q
        for name in panda.FINGER_JOINTS:
            q[self.model.jnt_qposadr[self.model.joint(name).id]] = panda.GRIPPER_OPEN
        return q

    def tcp_pose(self, arm_q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World position and rotation matrix of the tool centre at arm joint angles."""
        self.configuration.update(self.full_q(arm_q))
        transform = self.configuration.get_transform_frame_to_world(panda.TCP_SITE, "site")
        return transform.translation(), transform.rotation().as_matrix()

    def solve(self, position: np.ndarray, rotation: np.ndarray, start_q: np.ndarray) -> IKSolution:
        """Joint angles putting the tool centre at a world pose, from a starting configuration."""
        self.configuration.update(self.full_q(start_q))
        target = mink.SE3.from_rotation_and_translation(mink.SO3.from_matrix(rotation), np.asarray(position, float))
        self.tcp_task.set_target(target)
        tasks = [self.tcp_task, self.posture_task]
        for _ in range(_MAX_ITERATIONS):
            error = self.tcp_task.compute_error(self.configuration)
            if np.linalg.norm(error[:3]) < 1e-4 and np.linalg.norm(error[3:]) < 1e-3:
                break
            velocity = mink.solve_ik(self.configuration, tasks, _DT, "daqp", damping=1e-3, limits=self.limits)
            self.configuration.integrate_inplace(velocity, _DT)
        error = self.tcp_task.compute_error(self.configuration)
        q = self.configuration.q[self._qadr].copy()
        return IKSolution(q=q, position_error=float(np.linalg.norm(error[:3])),
                          orientation_error=float(np.linalg.norm(error[3:])))


_solvers: dict[str, ArmIK] = {}


def arm_ik(arm: str, base_pos: np.ndarray, base_quat: np.ndarray) -> ArmIK:
    """The IK solver of the arm named `arm`, placed at a base pose: compiled once per process.

    Every solve starts from the configuration it is given, so a re-posed solver answers
    exactly as a freshly compiled one would."""
    solver = _solvers.get(arm)
    if solver is None:
        solver = _solvers[arm] = ArmIK(base_pos, base_quat)
    else:
        solver.place(base_pos, base_quat)
    return solver
