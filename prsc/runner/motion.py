"""Driving a scene's arms in simulation: joint-space moves, the gripper, top-down tool paths via IK.

Any arm with a gripper (docs/assets.md, "Controllers for any arm"): the arm is the chain of
joints that moves its tool (prsc/runner/arm_scene.py), the gripper what its model's actuators
drive off that chain (prsc/runner/gripper.py), and the IK the one every arm uses
(prsc/user_assets/arm_ik.py). Home is the pose the episode starts in.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, TypeVar

import mujoco
import numpy as np

from prsc.assets.articulated import robot_model
from prsc.errors import PrscError
from prsc.runner.arm_scene import SceneArm, servos
from prsc.runner.gripper import Gripper, gripper_of
from prsc.runner.harness import snapshot
from prsc.user_assets.arm_ik import ArmFrames, random_starts, solve_top_down, turned

T = TypeVar("T")
CONTROL_STEPS = 5  # physics steps per control update (10 ms at the 2 ms timestep)
JOINT_SPEED = 1.2  # rad/s, average over a move (min-jerk peaks at 1.9x, under a Franka's 2.17)
MIN_MOVE_SECONDS = 0.4
LINE_STEP = 0.03  # m between IK points along a straight tool path (the descent onto a cube, the lift)
RESTARTS = 8  # starts drawn within the joint limits, tried after home and home turned towards a
# target: from home alone a 7-joint arm stalls at points it reaches


class Unreachable(Exception):
    """An IK target the arm cannot reach within tolerance."""

    def __init__(self, arm: str, label: str, miss: tuple[float, float]):
        super().__init__(f"{arm} cannot reach {label}: IK residual {miss[0] * 100:.1f} cm, "
                         f"{math.degrees(miss[1]):.1f} deg")


@dataclass(frozen=True)
class Arm:
    """One arm of the scene with its gripper: its joints and tool, servos, home and grasp yaw."""

    name: str
    model: mujoco.MjModel
    frames: ArmFrames
    drive: np.ndarray  # the servo of each arm joint
    gripper: Gripper
    home: np.ndarray  # the arm's joints when the episode starts
    root: np.ndarray  # where the arm's root stands
    heading: float  # azimuth of the tool about the root at home
    facing: tuple[np.ndarray, np.ndarray]  # the closing axis (tool frame) and the world direction it keeps
    scratch: mujoco.MjData  # the IK's own state

    @staticmethod
    def of(robot: dict, model: mujoco.MjModel, data: mujoco.MjData) -> "Arm":
        """The robot object `robot` (an arm, with its `body`) in the compiled model at the episode's
        start; PrscError when it has no gripper."""
        arm = SceneArm.of_robot(robot, robot_model(robot.get("model")), model)
        gripper = gripper_of(model, arm.prefix, arm.frames, arm.tool)
        if gripper is None:
            raise PrscError(f"Robot {robot['name']!r} has no gripper: no actuator of its model drives a joint off "
                            f"the chain that moves its tool {arm.tool!r}; the handover needs two arms with grippers")
        root, heading = arm.root_and_heading(model, data)
        # Grasps keep the closing axis where it points at home, turned level: the yaw of the tool at
        # home, as the cube lies square to the trays.
        along = arm.frames.tool_pose(data)[1] @ gripper.closing
        along[2] = 0.0
        return Arm(robot["name"], model, arm.frames, servos(model, arm.frames), gripper,
                   data.qpos[arm.frames.qpos].copy(), root, heading,
                   (gripper.closing, along / np.linalg.norm(along)), mujoco.MjData(model))

    def miss(self, q: np.ndarray, target: np.ndarray) -> tuple[float, float]:
        """(m, rad): how far the tool stays from `target` at joints `q`, and from pointing down."""
        self.scratch.qpos[self.frames.qpos] = q
        mujoco.mj_kinematics(self.model, self.scratch)
        position, rotation = self.frames.tool_pose(self.scratch)
        return float(np.linalg.norm(position - target)), math.acos(min(1.0, max(-1.0, -rotation[2, 2])))

    def solve(self, target: np.ndarray, q_start: np.ndarray) -> tuple[np.ndarray, bool]:
        """(joints, reached) putting the tool top-down at `target` with the grasp yaw, from `q_start`,
        every link above the base."""
        q, ok = solve_top_down(self.model, self.scratch, self.frames, np.asarray(target, float), q_start,
                               facing=self.facing)
        return q, ok and self.frames.above_base(self.scratch)

    def plan_line(self, start: np.ndarray, end: np.ndarray, q_start: np.ndarray, label: str) -> list[np.ndarray]:
        """Joint waypoints moving the tool straight from `start` to `end`, top-down, LINE_STEP apart."""
        start, end = np.asarray(start, float), np.asarray(end, float)
        count = max(1, int(np.ceil(np.linalg.norm(end - start) / LINE_STEP)))
        path, q = [], q_start
        for k in range(1, count + 1):
            point = start + (end - start) * k / count
            q, ok = self.solve(point, q)
            if not ok:
                raise Unreachable(self.name, label, self.miss(q, point))
            path.append(q)
        return path

    def plan_from_home(self, target: np.ndarray, label: str, then: Callable[[np.ndarray], T]) -> tuple[np.ndarray, T]:
        """Joints putting the tool top-down at `target`, sought from home, home turned towards it, then
        RESTARTS starts within the limits, and what `then` plans on from them: the first pose it can
        plan on from (else its Unreachable, or how far home's answer stayed)."""
        target = np.asarray(target, float)
        towards = turned(self.home, self.frames, self.heading,
                         math.atan2(target[1] - self.root[1], target[0] - self.root[0]))
        failure: Unreachable | None = None
        first: np.ndarray | None = None
        for start in (self.home, towards, *random_starts(self.frames, self.home, RESTARTS)):
            q, ok = self.solve(target, start)
            first = q if first is None else first
            if not ok:
                continue
            try:
                return q, then(q)
            except Unreachable as error:
                failure = failure or error
        raise failure or Unreachable(self.name, label, self.miss(first, target))

    def plan_point(self, target: np.ndarray, q_start: np.ndarray, label: str) -> np.ndarray:
        """Joints putting the tool top-down at `target`, from `q_start`."""
        q, ok = self.solve(target, q_start)
        if not ok:
            raise Unreachable(self.name, label, self.miss(q, target))
        return q


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
        points = np.vstack([self.data.ctrl[arm.drive].copy(), *path])
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
                self.data.ctrl[arm.drive] = points[i] + (points[i + 1] - points[i]) * min(frac, 1.0)
            mujoco.mj_step(self.model, self.data, nstep=CONTROL_STEPS)
        self._check_stable()

    def command_gripper(self, arm: Arm, closed: bool) -> None:
        """Set the gripper's controls to close (or open) it."""
        self.data.ctrl[arm.gripper.actuators] = arm.gripper.closed if closed else arm.gripper.opened

    def grip(self, arm: Arm, closed: bool, seconds: float) -> None:
        """Close (or open) the gripper and wait for it."""
        self.command_gripper(arm, closed)
        self.wait(seconds)

    def _check_stable(self) -> None:
        """Raise when the simulation diverged (NaN or exploded state)."""
        if not np.all(np.isfinite(self.data.qpos)) or np.abs(self.data.qvel).max(initial=0) > 1e3:
            raise FloatingPointError(f"simulation diverged at t={self.data.time:.2f} s")
