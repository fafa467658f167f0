"""One arm's differential IK problem in one MuJoCo model, as mink states it (docs/assets.md):
a FrameTask on the tool, the arm's joints within their limits (ArmLimit), and every other
joint of the model (a scene's cubes, another arm, the fingers) held by mink's DofFreezingTask,
so the arm's joints solve the problem as if the rest were deleted. One step is one mink QP.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import mink
import numpy as np

from prsc.user_assets.arm_frames import ArmFrames

if TYPE_CHECKING:
    import mujoco

SOLVER = "daqp"  # the QP solver mink's own examples use, a dependency of the project
# A step's joint displacement is the QP's velocity times DT, and the task's gain of 1 asks each
# step for the whole error: a Gauss-Newton step, so DT only scales the velocity.
DT = 1.0
DAMPING = 1e-4  # mink's Levenberg-Marquardt damping on every joint (the hand-written DLS's)
LM_DAMPING = 1e-3  # the task's damping, times its squared error: large steps far from the point are shortened
LIMIT_GAIN = 0.95  # the share of the distance to a limit one step may cover (mink's ConfigurationLimit's)
FREE_YAW = (1.0, 1.0, 0.0)  # orientation costs about the tool's x, y, z: the turn about its own axis is free
FIXED_YAW = (1.0, 1.0, 1.0)
# Problems kept (one per model and arm; each holds its model and an MjData): an episode's
# controller reuses its own every solve.
CACHED = 4


class ArmLimit(mink.Limit):
    """The arm's joints within [lower, upper] (ArmFrames' limits, LIMIT_MARGIN inside the model's):
    mink's ConfigurationLimit on the arm's joints only, each step covering at most LIMIT_GAIN of
    the way to a limit."""

    def __init__(self, nv: int, arm: ArmFrames) -> None:
        finite_lower, finite_upper = np.isfinite(arm.lower), np.isfinite(arm.upper)
        self.qpos_lower, self.lower = arm.qpos[finite_lower], arm.lower[finite_lower]
        self.qpos_upper, self.upper = arm.qpos[finite_upper], arm.upper[finite_upper]
        G = np.zeros((len(self.lower) + len(self.upper), nv))
        G[np.arange(len(self.upper)), arm.dofs[finite_upper]] = 1.0
        G[len(self.upper) + np.arange(len(self.lower)), arm.dofs[finite_lower]] = -1.0
        self.G = G

    def compute_qp_inequalities(self, configuration: mink.Configuration, dt: float) -> mink.Constraint:
        """G dq <= h: no joint past its limit after the step."""
        if not len(self.G):
            return mink.Constraint()
        q = configuration.q
        h = np.concatenate([self.upper - q[self.qpos_upper], q[self.qpos_lower] - self.lower])
        return mink.Constraint(G=self.G, h=LIMIT_GAIN * np.maximum(h, 0.0))


@dataclass
class ArmProblem:
    """mink's configuration of a model, the tool's FrameTask, the arm's limit and the held joints."""

    configuration: mink.Configuration
    task: mink.FrameTask
    limits: list[mink.Limit]
    constraints: list[mink.Task]

    @staticmethod
    def of(model: "mujoco.MjModel", arm: ArmFrames) -> "ArmProblem":
        """The problem of arm `arm` in `model` (built on first use, then reused: see CACHED)."""
        key = (id(model), arm.tool, arm.tool_is_site, tuple(arm.dofs.tolist()),
               tuple(arm.lower.tolist()), tuple(arm.upper.tolist()))
        cached = _problems.get(key)
        if cached is not None and cached[0] is model:
            return cached[1]
        task = mink.FrameTask(arm.tool, "site" if arm.tool_is_site else "body", position_cost=1.0,
                              orientation_cost=FREE_YAW, lm_damping=LM_DAMPING)
        held = sorted(set(range(model.nv)) - set(arm.dofs.tolist()))
        constraints = [mink.DofFreezingTask(model, held)] if held else []
        problem = ArmProblem(mink.Configuration(model), task, [ArmLimit(model.nv, arm)], constraints)
        if len(_problems) >= CACHED:
            _problems.pop(next(iter(_problems)))
        _problems[key] = (model, problem)  # the model is kept alive with its key, so its id is not reused
        return problem

    def start(self, qpos: np.ndarray, free_yaw: bool) -> None:
        """Start a solve from the model's joint values `qpos`, the turn about the tool's own axis
        left free when `free_yaw`."""
        self.configuration.update(qpos)
        self.task.set_orientation_cost(FREE_YAW if free_yaw else FIXED_YAW)

    def step(self, target: np.ndarray) -> None:
        """One mink step towards the tool's pose `target` (wxyz quaternion, then xyz, in the world)."""
        self.task.set_target(mink.SE3(wxyz_xyz=target))
        velocity = mink.solve_ik(self.configuration, [self.task], DT, SOLVER, damping=DAMPING,
                                 limits=self.limits, constraints=self.constraints)
        self.configuration.integrate_inplace(velocity, DT)


_problems: dict[tuple, tuple["mujoco.MjModel", ArmProblem]] = {}
