"""Inverse kinematics of one Panda with mink, on an arm-only model placed like the scene's arm."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Iterator

import mink
import mujoco
import numpy as np

from prsc.assets import panda

# Reached means: tool centre within 5 mm and 3 degrees of the target.
POSITION_TOLERANCE = 0.005
ORIENTATION_TOLERANCE = np.radians(3.0)
_MAX_ITERATIONS = 300
_DT = 0.05
# Starts drawn within the joint limits, tried after home and home turned towards the target: from
# home alone the 7-joint arm stalls at points it reaches (at +-75 and 165 degrees about the base
# the reach seemed to end at 0.64 m at the table's height, where the neighbours reach 0.8 m).
RESTARTS = 8
# m two of the arm's own links may overlap before a pose counts as colliding with itself: the
# collision meshes of neighbours two links apart overlap by a few mm in ordinary poses.
SELF_PENETRATION = 0.005
LINE_STEP = 0.03  # m between IK points along a straight tool path (the controller's descent and lift)


@dataclass(frozen=True)
class IKSolution:
    """Arm joint angles for a target, and how far the tool centre stays from the target."""

    q: np.ndarray
    position_error: float
    orientation_error: float
    self_collision: bool = False  # the pose puts one of the arm's links into another

    @property
    def reached(self) -> bool:
        """Whether the target was reached within tolerance, by a pose free of the arm itself."""
        return (self.position_error <= POSITION_TOLERANCE and self.orientation_error <= ORIENTATION_TOLERANCE
                and not self.self_collision)


class ArmIK:
    """Solves tool-centre poses for one arm whose base sits at a given world pose."""

    def __init__(self, base_pos: np.ndarray, base_quat: np.ndarray):
        spec = panda.panda_mjcf_spec()
        # The arm alone, with its own collision meshes: which poses put a link into another.
        self._collider = spec.compile()
        self._collider_data = mujoco.MjData(self._collider)
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
        lower, upper = self.model.jnt_range[[self.model.joint(j).id for j in panda.ARM_JOINTS]].T
        self._random_starts = list(np.random.default_rng(0).uniform(lower, upper, (RESTARTS, len(lower))))
        self._first_joint = (float(lower[0]), float(upper[0]))
        self._last_joint = (float(lower[-1]), float(upper[-1]))

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

    def solutions_from_home(self, position: np.ndarray, rotation: np.ndarray) -> Iterator[IKSolution]:
        """Every start's answer for a world pose, in order: home, home turned towards it, then RESTARTS
        starts within the joint limits (the same every call). A caller that must go on from the pose
        (down to a cube, up again) takes the first reached one it can go on from; home's answer says
        how far the IK stayed when none is reached."""
        home = np.array(panda.HOME_QPOS)
        for start in (home, self._turned(home, np.asarray(position, float)), *self._random_starts):
            yield self.solve_free(position, rotation, start)

    def solve_from_home(self, position: np.ndarray, rotation: np.ndarray) -> IKSolution:
        """The first reached of `solutions_from_home`, else home's answer."""
        first = None
        for solution in self.solutions_from_home(position, rotation):
            if solution.reached:
                return solution
            first = first or solution
        assert first is not None
        return first

    def solve_line(self, start: np.ndarray, end: np.ndarray, rotation: np.ndarray, start_q: np.ndarray,
                   free: bool = False) -> list[IKSolution]:
        """Solutions along the tool's straight path from `start` to `end` (LINE_STEP apart, each from the
        one before), up to the first not reached, which ends the list; `free` marks self-collisions too."""
        start, end = np.asarray(start, float), np.asarray(end, float)
        count = max(1, int(np.ceil(np.linalg.norm(end - start) / LINE_STEP)))
        solve = self.solve_free if free else self.solve
        path, q = [], start_q
        for k in range(1, count + 1):
            path.append(solve(start + (end - start) * k / count, rotation, q))
            if not path[-1].reached:
                break
            q = path[-1].q
        return path

    def solve_free(self, position: np.ndarray, rotation: np.ndarray, start_q: np.ndarray) -> IKSolution:
        """`solve`, its answer marked when the pose puts one of the arm's links into another."""
        solution = self.solve(position, rotation, start_q)
        return replace(solution, self_collision=self.self_collides(solution.q))

    def self_collides(self, arm_q: np.ndarray) -> bool:
        """Whether two links of the arm that are not parent and child overlap at these joint angles
        (by more than SELF_PENETRATION): a top-down pose beside the base puts the hand into it."""
        data = self._collider_data
        data.qpos[:] = self.full_q(arm_q)
        mujoco.mj_kinematics(self._collider, data)
        mujoco.mj_collision(self._collider, data)
        return bool(np.any(data.contact.dist[:data.ncon] < -SELF_PENETRATION))

    def _turned(self, home: np.ndarray, target: np.ndarray) -> np.ndarray:
        """Home with the base joint turned so that the tool heads towards the target (within its
        limits), and the wrist turned back by as much (by a full turn more or less where that is
        within its limits), so the hand keeps home's orientation: the IK need not turn it."""
        base = self.model.body_pos[self._base]
        tool = self.tcp_pose(home)[0]
        turn = np.arctan2(target[1] - base[1], target[0] - base[0]) - np.arctan2(tool[1] - base[1], tool[0] - base[0])
        q = home.copy()
        q[0] = float(np.clip(q[0] + (turn + np.pi) % (2 * np.pi) - np.pi, *self._first_joint))
        low, high = self._last_joint
        wrist = [q[6] + q[0] - home[0] + k * 2 * np.pi for k in (0, -1, 1)]
        q[6] = next((w for w in wrist if low <= w <= high), q[6])
        return q


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
