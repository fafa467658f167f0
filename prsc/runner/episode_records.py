"""What crosses process lines in a campaign: episode tasks, results and how to record them (this module imports no mujoco,
so a worker can unpickle a task before it chooses its GL backend)."""

from __future__ import annotations

from dataclasses import dataclass, field

from prsc.runner.controller import ControllerRef

DEFAULT_MAX_SIM_SECONDS = 600.0
RESERVED_KEYS = ("index", "seed", "sim_seconds", "wall_seconds", "task")


@dataclass(frozen=True)
class EpisodeTask:
    """One episode to run: its index in the campaign, the scene JSON, its compiled MJCF, the seed
    to record, the controller and the simulated-time limit."""

    index: int
    scene: dict
    mjcf_path: str
    seed: int
    controller: ControllerRef
    max_sim_seconds: float = DEFAULT_MAX_SIM_SECONDS
    monitor_task: bool = True  # watch the scene's task, when it has one (`prsc bench --episodes --no-task` does not)


@dataclass(frozen=True)
class EpisodeResult:
    """One line of results.jsonl: index, seed, outcome, reason, the controller's own keys, times."""

    index: int
    seed: int
    outcome: str
    reason: str
    sim_seconds: float
    wall_seconds: float
    extra: dict = field(default_factory=dict)
    # The scene's task over the episode (prsc/task/monitor.py: outcome, trivial, decided_at,
    # robustness, records), beside the controller's own outcome; None when the scene has no task.
    task: dict | None = None

    def to_json(self) -> dict:
        """The JSON object written to results.jsonl (the controller's keys between reason and the times)."""
        out = {"index": self.index, "seed": self.seed, "outcome": self.outcome, "reason": self.reason,
               **self.extra, "sim_seconds": self.sim_seconds, "wall_seconds": self.wall_seconds}
        if self.task is not None:
            out["task"] = self.task
        return out

    @classmethod
    def from_json(cls, record: dict) -> EpisodeResult:
        """The result a results.jsonl line holds."""
        fixed = ("outcome", "reason", *RESERVED_KEYS)
        return cls(index=int(record["index"]), seed=int(record["seed"]), outcome=str(record["outcome"]),
                   reason=str(record["reason"]), sim_seconds=float(record["sim_seconds"]),
                   wall_seconds=float(record["wall_seconds"]),
                   extra={k: v for k, v in record.items() if k not in fixed}, task=record.get("task"))



@dataclass(frozen=True)
class RecordSettings:
    """How a campaign records a dataset (docs/datasets.md): format, frames per simulated second,
    lossless video, whether the cameras are rendered, the task text (empty: the spec's)."""

    format: str
    fps: int
    lossless: bool = False
    images: bool = True
    task: str = ""
