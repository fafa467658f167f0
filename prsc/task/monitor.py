"""An episode's task over time: goals held for their window, the first failure, the time limit, and
the records; the outcome and each statement's robustness (docs/tasks.md)."""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

from prsc.task.robustness import Evaluator, json_value
from prsc.task.terms import Task
from prsc.task.world import WorldState

TIME_SLACK = 1e-9  # s: a window or a limit reached up to rounding counts as reached


@dataclass(frozen=True)
class TaskStatus:
    """The task at one time: its outcome so far (None while undecided, else "success", "fail:LABEL" or
    "timeout") and each statement's robustness now (positive is good: "goal", "fail:LABEL")."""

    time: float
    outcome: str | None
    goal_robustness: float
    robustness: dict[str, float] = field(default_factory=dict)


class _Window:
    """The minimum of a signal over the last `length` seconds (a monotonic deque), and the current
    run of samples where it held."""

    def __init__(self, length: float):
        self.length = length
        self.samples: deque[tuple[float, float]] = deque()
        self.run_start: float | None = None

    def push(self, time: float, value: float, holds: bool) -> float:
        while self.samples and self.samples[-1][1] >= value:
            self.samples.pop()
        self.samples.append((time, value))
        while self.samples[0][0] < time - self.length - TIME_SLACK:
            self.samples.popleft()
        if not holds:
            self.run_start = None
        elif self.run_start is None:
            self.run_start = time
        return self.samples[0][1]

    def held(self, time: float) -> bool:
        return self.run_start is not None and time - self.run_start >= self.length - TIME_SLACK


class EpisodeMonitor:
    """Feeds world states, one per control step, to a task; decides the outcome once."""

    def __init__(self, task: Task):
        self.task = task
        self.evaluator = Evaluator(task)
        statements = task.statements
        self.windows = [_Window(g.hold) for g in statements.goals]
        self.start: float | None = None
        self.time = 0.0
        self.outcome: str | None = None
        self.decided_at: float | None = None
        self.trivial = False
        self.best_goal = -math.inf
        self.worst_failure = {f.label: -math.inf for f in statements.failures}
        self.records: dict[str, object] = {r.name: [] for r in statements.records if r.when == "step"}
        # each statement as a function of the world state, made once (updates run at every control step)
        self._goals = [(self.evaluator.compiled(g.expr), g.hold, w) for g, w in zip(statements.goals, self.windows)]
        self._failures = [(self.evaluator.compiled(f.expr), f.label, f"fail:{f.label}") for f in statements.failures]
        self._has_goals = bool(statements.goals)
        # the records read at a step: every step's, and at the first also the initial ones
        self._step_records = [r for r in statements.records if r.when == "step"]
        self._first_records = [r for r in statements.records if r.when in ("step", "initial")]

    def update(self, world: WorldState) -> TaskStatus:
        """Evaluate every statement at `world.time`; the status after it."""
        time = float(world.time)
        first = self.start is None
        if first:
            self.start = time
        self.time = time
        robustness: dict[str, float] = {}
        goal_value = math.inf
        goals_hold = self._has_goals
        all_now = True
        for goal, hold, window in self._goals:
            truth = goal(world)
            all_now = all_now and truth.holds
            value = window.push(time, truth.robustness, truth.holds)
            if time - self.start < hold - TIME_SLACK:  # type: ignore[operator]
                value = min(value, 0.0)  # a window the episode has not filled yet has not held
            if value < goal_value:
                goal_value = value
            goals_hold = goals_hold and window.held(time)
        if self._has_goals:
            if goal_value > self.best_goal:
                self.best_goal = goal_value
            robustness["goal"] = goal_value
            if first:
                self.trivial = all_now
        failed = None
        worst = self.worst_failure
        for failure, label, key in self._failures:
            truth = failure(world)
            if truth.robustness > worst[label]:
                worst[label] = truth.robustness
            robustness[key] = -truth.robustness
            if truth.holds and failed is None:
                failed = label
        for record in self._step_records if not first else self._first_records:
            value = json_value(self.evaluator.value(record.expr, world))
            if record.when == "step":
                self.records[record.name].append(value)  # type: ignore[union-attr]
            else:
                self.records[record.name] = value
        if self.outcome is None:
            limit = self.task.statements.time_limit
            if failed is not None:
                self._decide(f"fail:{failed}", time)
            elif goals_hold:
                self._decide("success", time)
            elif limit is not None and time - self.start >= limit - TIME_SLACK:  # type: ignore[operator]
                self._decide("timeout", time)
        return TaskStatus(time, self.outcome, goal_value if self._has_goals else math.nan, robustness)

    def _decide(self, outcome: str, time: float) -> None:
        self.outcome, self.decided_at = outcome, time

    def result(self, world: WorldState | None, controller_finished: bool) -> dict:
        """The episode's task record: outcome, trivial, decided_at, robustness, records ("final" read from world)."""
        for record in self.task.statements.records:
            if record.when == "final" and world is not None:
                self.records[record.name] = json_value(self.evaluator.value(record.expr, world))
        outcome = self.outcome
        if outcome is None:
            outcome = "incomplete" if controller_finished else "timeout"
        robustness = {}
        if self.task.statements.goals:
            robustness["goal"] = _finite(self.best_goal)
        for label, worst in self.worst_failure.items():
            robustness[f"fail:{label}"] = _finite(-worst)
        return {"outcome": outcome, "trivial": self.trivial, "decided_at": self.decided_at,
                "robustness": robustness, "records": dict(self.records)}


def _finite(value: float) -> float | None:
    """A robustness as JSON holds it (None when the episode had no step)."""
    return float(value) if math.isfinite(value) else None
