"""Driving the scene's Pandas in simulation: joint-space moves, gripper, Cartesian paths via IK."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, TypeVar

import mujoco
import numpy as np

from prsc.assets import panda
from prsc.runner.harness import snapshot
from prsc.runner.ik import ArmIK, IKSolution, arm_ik

T = TypeVar("T")
CONTROL_STEPS = 5  # physics steps per control update (10 ms at the 2 ms timestep)
JOINT_SPEED = 1.2  # rad/s, average over a move (min-jerk peaks at 1.9x, under the Panda's 2.17)
MIN_MOVE_SECONDS = 0.4


class Unreachable(Exception):
    """An IK target the arm cannot reach within tolerance."""

    def __init__(self, arm: str, label: str, solution: IKSolution):
        super().__init__(
            f"{arm} cannot reach {label}: IK residual {solution.position_error * 100:.1f} cm, "
            f"{np.degrees(solution.orientation_error):.1f} deg"
            + (" (the pose puts the arm into itself)" if solution.self_collision else "")
        )
        self.solution = solution


@dataclass
class Arm:
    """One Panda of the scene: its joints, actuators and tool site, and an IK solver."""

    name: str
    qpos_adr: np.ndarray
    ctrl_ids: np.ndarray
    gripper_id: int
    finger_adr: int
    tcp_id: int
    ik: ArmIK
    down: np.ndarray  # tool orientation for top-down grasps (the home orientation)

    @classmethod
    def from_scene(cls, model: mujoco.MjModel, data: mujoco.MjData, name: str) -> Arm:
        """Find the Panda attached with prefix `<name>/` in a compiled scene."""
        def joint_adr(joint: str) -> int:
            return int(model.jnt_qposadr[model.joint(f"{name}/{joint}").id])

        base = data.body(f"{name}/{panda.BASE_BODY}")
        ik = arm_ik(name, base.xpos.copy(), base.xquat.copy())
        return cls(
            name=name,
            qpos_adr=np.array([joint_adr(j) for j in panda.ARM_JOINTS]),
            ctrl_ids=np.array([model.actuator(f"{name}/{a}").id for a in panda.ARM_ACTUATORS]),
            gripper_id=model.actuator(f"{name}/{panda.GRIPPER_ACTUATOR}").id,
            finger_adr=joint_adr(panda.FINGER_JOINTS[0]),
            tcp_id=model.site(f"{name}/{panda.TCP_SITE}").id,
            ik=ik,
            down=ik.tcp_pose(np.array(panda.HOME_QPOS))[1],
        )

    def plan_line(self, start: np.ndarray, end: np.ndarray, q_start: np.ndarray, label: str) -> list[np.ndarray]:
        """Joint waypoints moving the tool centre straight from `start` to `end`, top-down (ArmIK.solve_line)."""
        path = self.ik.solve_line(start, end, self.down, q_start)
        if not path[-1].reached:
            raise Unreachable(self.name, label, path[-1])
        return [solution.q for solution in path]

    def plan_from_home(self, target: np.ndarray, label: str, then: Callable[[np.ndarray], T]) -> tuple[np.ndarray, T]:
        """Joint angles putting the tool centre top-down at `target`, sought from home as `reachable by`
        was built (ArmIK.solutions_from_home), and what `then` plans on from them: the first pose it can
        plan on from (else its Unreachable)."""
        failure: Unreachable | None = None
        home: IKSolution | None = None
        for solution in self.ik.solutions_from_home(target, self.down):
            home = home or solution
            if not solution.reached:
                continue
            try:
                return solution.q, then(solution.q)
            except Unreachable as error:
                failure = failure or error
        assert home is not None
        raise failure or Unreachable(self.name, label, home)

    def plan_point(self, target: np.ndarray, q_start: np.ndarray, label: str) -> np.ndarray:
        """Joint angles putting the tool centre top-down at `target`."""
        solution = self.ik.solve(target, self.down, q_start)
        if not solution.reached:
            raise Unreachable(self.name, label, solution)
        return solution.q


class Simulation:
    """Steps a scene, interpolating arm targets smoothly; names key moments for frame strips."""

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData):
        self.model = model
        self.data = data

    def snapshot(self, label: str) -> None:
        """Offer the current state to a frame recorder (`prsc run --video`)."""
        snapshot(label, self.model, self.data)

    def wait(self, seconds: float) -> None:
        """Advance physics with the current controls."""
        steps = max(1, int(round(seconds / self.model.opt.timestep)))
        mujoco.mj_step(self.model, self.data, nstep=steps)
        self._check_stable()

    def move(self, arm: Arm, path: list[np.ndarray], seconds: float | None = None) -> None:
        """Track a joint path (piecewise linear, min-jerk timed) from the current targets."""
        points = np.vstack([self.data.ctrl[arm.ctrl_ids].copy(), *path])
        lengths = np.abs(np.diff(points, axis=0)).max(axis=1)
        total = float(lengths.sum())
        if seconds is None:
            seconds = max(MIN_MOVE_SECONDS, total / JOINT_SPEED)
        cumulative = np.concatenate([[0.0], np.cumsum(lengths)])
        dt = self.model.opt.timestep * CONTROL_STEPS
        updates = max(1, int(round(seconds / dt)))
        for k in range(1, updates + 1):
            tau = k / updates
            s = (10 * tau**3 - 15 * tau**4 + 6 * tau**5) * total
            if total > 0:
                i = min(int(np.searchsorted(cumulative, s, side="right")) - 1, len(lengths) - 1)
                frac = 0.0 if lengths[i] == 0 else (s - cumulative[i]) / lengths[i]
                self.data.ctrl[arm.ctrl_ids] = points[i] + (points[i + 1] - points[i]) * min(frac, 1.0)
            mujoco.mj_step(self.model, self.data, nstep=CONTROL_STEPS)
        self._check_stable()

    def grip(self, arm: Arm, opening: float, seconds: float) -> None:
        """Command the gripper opening and wait for it."""
        self.data.ctrl[arm.gripper_id] = opening
        self.wait(seconds)

    def _check_stable(self) -> None:
        """Raise when the simulation diverged (NaN or exploded state)."""
        if not np.all(np.isfinite(self.data.qpos)) or np.abs(self.data.qvel).max(initial=0) > 1e3:
            raise FloatingPointError(f"simulation diverged at t={self.data.time:.2f} s")
