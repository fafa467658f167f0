"""The task in a step-by-step loop (prsc.SceneEnv, a user's own loop): per step, the reward, whether
the episode terminated (goal reached or a failure held) or was truncated (`terminate after`),
and the task's status and robustness for `info`."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco

from prsc.runner.task_monitor import TaskMonitor, TaskStatus

REWARDS = ("sparse", "dense")
"""sparse: 1 on success, else 0; dense: the goal's robustness now (m)."""


@dataclass(frozen=True)
class TaskStep:
    """What one step of the task gives a learning loop."""

    reward: float
    terminated: bool
    truncated: bool
    info: dict


class TaskSteps:
    """A TaskMonitor per episode, read once per environment step."""

    def __init__(self, reward: str = "sparse"):
        if reward not in REWARDS:
            raise ValueError(f"reward must be a function or one of {', '.join(REWARDS)}, got {reward!r}")
        self.reward = reward
        self.monitor: TaskMonitor | None = None

    def reset(self, scene: dict, model: mujoco.MjModel, data: mujoco.MjData) -> dict:
        """Start watching a new episode (its initial state counts: a goal that holds now is `trivial`)."""
        self.monitor = TaskMonitor(scene, model)
        return self._info(self.monitor.update(model, data))

    def step(self, model: mujoco.MjModel, data: mujoco.MjData) -> TaskStep:
        """The task after a step."""
        assert self.monitor is not None, "reset first"
        status = self.monitor.update(model, data)
        success = status.outcome == "success"
        reward = (1.0 if success else 0.0) if self.reward == "sparse" else float(status.goal_robustness)
        return TaskStep(reward, status.outcome in ("success",) or (status.outcome or "").startswith("fail:"),
                        status.outcome == "timeout", self._info(status))

    def _info(self, status: TaskStatus) -> dict:
        return {"is_success": status.outcome == "success",
                "task": {"time": status.time, "outcome": status.outcome, "trivial": self.monitor.monitor.trivial,  # type: ignore[union-attr]
                         "goal_robustness": status.goal_robustness, "robustness": dict(status.robustness)}}
