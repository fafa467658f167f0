"""What `prsc falsify` counts as a failure of one episode, and how close the episode came to it.

The one place that reads an episode's task record (`record["task"]`, written by the task
monitor of `prsc run`: docs/tasks.md):

    "task": {"outcome": "success" | "fail:LABEL" | "timeout" | "incomplete", "trivial": bool,
             "decided_at": float | null, "robustness": {"goal": float, "fail:LABEL": float, ...},
             "records": {...}}

A failure condition's robustness is minus the largest value its EXPR reached (positive: the
episode stayed away from failing; negative: it failed), the goal's the largest value its
window reached (negative: never reached). Without a task in the spec the record has no
"task" and the controller's own outcome label decides, with no robustness.
"""

from __future__ import annotations

from dataclasses import dataclass

from prsc.errors import PrscError

STEERS = ("robustness", "label")  # what moves the proposal: the episodes nearest to failing, or the failures alone
GOAL = "goal"  # --property goal: the task's outcome is not success, steered by the goal's robustness


@dataclass(frozen=True)
class Verdict:
    """One episode judged against the property: failed or not, its robustness (None: unknown) and its label."""

    failed: bool
    robustness: float | None  # metres (the task's unit): > 0 stayed away from failing, <= 0 failed
    label: str  # the outcome that counts: the task's, or the controller's without a task
    from_task: bool  # judged on the task monitor's record (else on the controller's outcome)


def check_property(prop: str | None, failure_labels: tuple[str, ...] | None) -> None:
    """Refuse `--property` before any episode runs: a spec without a task (labels None), or a label it lacks."""
    if prop is None or (failure_labels is not None and (prop == GOAL or prop in failure_labels)):
        return
    if failure_labels is None:
        raise PrscError(f"--property {prop}: the spec states no task (docs/tasks.md), so episodes have only "
                        "the controller's outcome; drop --property to count every outcome but success")
    labels = ", ".join(sorted(failure_labels)) or "none"
    raise PrscError(f"--property {prop}: the spec's task has no `fail \"{prop}\" when ...` "
                    f"(its failure labels: {labels}; or --property {GOAL})")


def episode_verdict(record: dict, prop: str | None) -> Verdict:
    """The episode against `prop`: None (any task outcome but success), "goal", or a fail LABEL of the spec's task."""
    task = record.get("task")
    if task is None:
        if prop is not None:
            raise PrscError(f"--property {prop}: the spec states no task (docs/tasks.md), so episodes have only "
                            "the controller's outcome; drop --property to count every outcome but success")
        return Verdict(record["outcome"] != "success", None, record["outcome"], False)
    outcome, robustness = task["outcome"], task.get("robustness") or {}
    if prop is None:  # success needs the goal reached and no failure: the least of their margins
        values = [float(v) for v in robustness.values() if v is not None]
        return Verdict(outcome != "success", min(values) if values else None, outcome, True)
    if prop == GOAL:
        value = robustness.get(GOAL)
        return Verdict(outcome != "success", None if value is None else float(value), outcome, True)
    key = f"fail:{prop}"
    if key not in robustness:
        labels = ", ".join(sorted(k[5:] for k in robustness if k.startswith("fail:"))) or "none"
        raise PrscError(f"--property {prop}: the spec's task has no `fail \"{prop}\" when ...` "
                        f"(its failure labels: {labels}; or --property {GOAL})")
    value = robustness[key]
    return Verdict(outcome == key, None if value is None else float(value), outcome, True)
