"""One episode of any controller: load the compiled MJCF, call the controller, record what it returns.

The harness owns what every controller shares: a fresh MjModel/MjData from the file (at
its `home` keyframe when it has one), the simulated-time limit (outcome `timeout`), a
controller's exception (outcome `error`), and the line of results.jsonl. Infrastructure
faults (the file does not load, no GL context) raise InfrastructureError instead.
"""

from __future__ import annotations

import contextlib
import json
import signal
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import mujoco

from prsc.backends.names import with_body_names

from prsc.runner.controller import load_controller
from prsc.runner.faults import InfrastructureError, SimulationTimeLimit
from prsc.runner.step_hook import PeriodicCallback, StepHook, raise_from_signal
from prsc.runner.task_monitor import CONTROL_PERIOD, TaskMonitor
from prsc.runner.episode_records import RESERVED_KEYS, EpisodeResult, EpisodeTask

Observer = Callable[[str, mujoco.MjModel, mujoco.MjData], None]
_observer: Observer | None = None


def snapshot(label: str, model: mujoco.MjModel, data: mujoco.MjData) -> None:
    """Called by a controller at moments worth a frame (`prsc run --video`); free when nobody records."""
    if _observer is not None:
        _observer(label, model, data)


def load_model(mjcf_path: str | Path) -> mujoco.MjModel:
    """The compiled MJCF as MuJoCo loads it, options untouched; InfrastructureError when it cannot."""
    try:
        return mujoco.MjModel.from_xml_path(str(mjcf_path))
    except (ValueError, mujoco.FatalError) as error:
        raise InfrastructureError(f"MuJoCo cannot load {mjcf_path}: {str(error).strip()}") from None


def fresh_data(model: mujoco.MjModel) -> mujoco.MjData:
    """MjData at the model's `home` keyframe (the scene's poses, robots at home), forward-computed."""
    data = mujoco.MjData(model)
    key = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, "home")
    if key >= 0:
        mujoco.mj_resetDataKeyframe(model, data, key)
    mujoco.mj_forward(model, data)
    return data


def _interpret(returned) -> tuple[str, str, dict]:
    """(outcome, reason, extra keys) of what a controller returned, or an `error` saying what is wrong."""
    if not isinstance(returned, dict):
        return "error", f"the controller returned {type(returned).__name__}, not a dict", {}
    outcome, reason = returned.get("outcome"), returned.get("reason")
    if not isinstance(outcome, str) or not outcome or not isinstance(reason, str):
        return "error", f"the controller's dict needs string 'outcome' and 'reason', got {outcome!r} and {reason!r}", {}
    extra = {k: v for k, v in returned.items() if k not in ("outcome", "reason")}
    clash = [k for k in extra if k in RESERVED_KEYS or not isinstance(k, str)]
    if clash:
        return "error", f"the controller's dict may not set {', '.join(map(repr, clash))} (the runner records them)", {}
    try:
        extra = json.loads(json.dumps(extra))
    except (TypeError, ValueError) as error:
        return "error", f"the controller's dict is not JSON-serialisable: {error}", {}
    return outcome, reason, extra


WATCH_SECONDS = 0.01  # how often (wall clock) the watchdog reads the episode's simulated time


class _Watchdog:
    """The simulated-time limit of an episode, without touching `mujoco.mj_step`: a timer reads
    `data.time` every WATCH_SECONDS and ends the episode past the limit (and, for `--video`,
    records a frame each `every` simulated seconds).

    MuJoCo's own control callback cannot do this: while one is installed no model compiles,
    and controllers compile models (IK, planning) mid-episode. Python runs the timer's handler
    between bytecodes of the main thread, so a runaway loop of `mj_step` calls ends within one
    tick; elsewhere (a thread) the limit is checked when the controller returns."""

    def __init__(self, data: mujoco.MjData, limit: float, every: float | None):
        self.data = data
        self.limit = limit
        self.every = every
        self.next_frame = 0.0
        self.armed = threading.current_thread() is threading.main_thread()

    def _tick(self, signum, frame) -> None:
        if self.data.time > self.limit:
            raise_from_signal(SimulationTimeLimit(), frame)  # inside a step hook's ctypes callback too
        if self.every is not None and _observer is not None and self.data.time >= self.next_frame:
            self.next_frame = self.data.time + self.every
            _observer(f"t = {self.data.time:.1f} s", self._model, self.data)

    def __call__(self, model: mujoco.MjModel) -> "_Watchdog":
        self._model = model
        return self

    def __enter__(self) -> "_Watchdog":
        if self.armed:
            self._previous = signal.signal(signal.SIGALRM, self._tick)
            signal.setitimer(signal.ITIMER_REAL, WATCH_SECONDS, WATCH_SECONDS)
        return self

    def __exit__(self, *exc) -> None:
        if self.armed:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, self._previous)


def run_episode(task: EpisodeTask, observer: Observer | None = None, frame_every: float | None = None,
                step_callbacks: Sequence[PeriodicCallback] = (),
                monitor_ready: Callable[[TaskMonitor], None] | None = None) -> EpisodeResult:
    """Run one episode of the task's controller and classify it; infrastructure faults raise.
    `step_callbacks` watch the episode's own data from inside mj_step (a dataset recorder), after the
    task's monitor, which `monitor_ready` is given once built (its `latest` status is each frame's)."""
    global _observer
    started = time.perf_counter()
    controller = load_controller(task.controller)
    model = load_model(task.mjcf_path)
    data = fresh_data(model)
    _observer = observer
    sim_seconds = None  # the time to record, when the watchdog stopped the episode (data.time is past it by a tick)
    monitor = TaskMonitor(task.scene, model) if task.monitor_task and task.scene.get("task") else None
    limit = task.max_sim_seconds
    if monitor is not None and monitor.task.statements.time_limit is not None:
        limit = min(limit, monitor.task.statements.time_limit)  # `terminate after` bounds the episode
    # The task is watched from inside the episode's own mj_step (prsc/runner/step_hook.py): the
    # controller does not co-operate, and its own models (IK, planning) never reach the monitor.
    # A monitor that fails ends the task's watch, not the episode; a recorder that fails is a fault.
    monitor_failure: list[Exception] = []

    # A recorder reads each step's status as the step happens; otherwise the monitor logs the
    # states and evaluates them together (TaskMonitor.log: the same statuses, at half the cost).
    watch = None if monitor is None else monitor.update if monitor_ready is not None else monitor.log

    def watch_task(m: mujoco.MjModel, d: mujoco.MjData) -> None:
        if not monitor_failure:
            try:
                watch(m, d)
            except Exception as error:  # noqa: BLE001 - kept for the record
                monitor_failure.append(error)

    if monitor is not None and monitor_ready is not None:
        monitor_ready(monitor)
    watchers = [PeriodicCallback(CONTROL_PERIOD, watch_task)] if monitor is not None else []
    callbacks = [*watchers, *step_callbacks]
    # no control callback at all when nothing watches: every mj_step of the process would pay for it
    hook = StepHook(model, data, callbacks) if callbacks else None
    finished = True
    try:
        with _Watchdog(data, limit, frame_every)(model), hook or contextlib.nullcontext():
            returned = controller(with_body_names(task.scene), model, data)
        outcome, reason, extra = _interpret(returned)
    except SimulationTimeLimit:
        outcome, reason, extra = "timeout", f"still running after {limit:g} simulated seconds", {}
        sim_seconds = limit  # where it stopped depends on the wall clock: the record must not
        finished = False
    except InfrastructureError:
        raise
    except Exception as error:  # the controller's own failure is an outcome, and the campaign goes on
        message = str(error).strip().splitlines()
        outcome, reason, extra = "error", f"{type(error).__name__}: {message[0] if message else ''}".rstrip(": "), {}
    finally:
        _observer = None
    if hook is not None and hook.error is not None and not isinstance(hook.error, SimulationTimeLimit):  # the limit's tick may land in a callback
        raise InfrastructureError(f"a step callback failed: {type(hook.error).__name__}: {hook.error}")
    if outcome != "timeout" and data.time > limit:
        outcome, reason, extra = "timeout", f"ran {data.time:g} simulated seconds, past the limit of {limit:g}", {}
        finished = False
    task_record = None
    if monitor is not None:
        try:
            if monitor_failure:
                raise monitor_failure[0]
            task_record = monitor.result(model, data, controller_finished=finished)  # evaluates any logged states
        except Exception as error:  # noqa: BLE001 - the record says so
            # the monitor failed (a bug, or a task the scene's model cannot answer)
            task_record = {"outcome": "error", "trivial": False, "decided_at": None, "robustness": {}, "records": {},
                           "reason": f"{type(error).__name__}: {error}"}
    return EpisodeResult(
        index=task.index,
        seed=int(task.seed),
        outcome=outcome,
        reason=reason,
        sim_seconds=round(float(data.time if sim_seconds is None else sim_seconds), 3),
        wall_seconds=round(time.perf_counter() - started, 3),
        extra=extra,
        task=task_record,
    )
