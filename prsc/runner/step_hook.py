"""Callbacks on one episode's own MjData at a period of simulated time, called from inside
`mujoco.mj_step` whoever calls it: the task monitor and the dataset recorder watch an episode
without the controller's co-operation and without patching `mujoco.mj_step`.

MuJoCo's control callback (`mjcb_control`) is global: every model's `mj_step` and `mj_forward`
calls it. A Python callable there also breaks compiling any model ("engine error: Python
exception raised": the binding cannot wrap the compiler's own mjData), so a controller that
builds an IK or planning model mid-episode failed. A ctypes function pointer is called with raw
pointers instead: the hook returns at once for every mjData but the episode's, and the
controller's own models compile and step as before (about 0.4 us a call, measured).

Where the hook runs, MuJoCo has computed the step's positions, contacts and velocities for
`data.time`, and `data.ctrl` holds what the controller set before the step: a callback sees a
consistent state. It may not step the episode's data itself.

An exception cannot cross MuJoCo's C frames from a ctypes callback (ctypes prints and drops it).
So a callback's exception, a request to stop the episode (`stop`), and a signal handler's
exception that Python happens to run inside the callback (the watchdog's SIGALRM, a SIGINT:
`raise_from_signal`) are kept as pending, and a Python callable that raises it is swapped in:
the episode's next `mj_step` raises it with its own type, before actuation and integration, so
the state is that of a clean run. Until that step, a model compiled by the controller would
fail, as with any Python control callback; the window is one step of the episode.
"""

from __future__ import annotations

import ctypes
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import mujoco

StepCallback = Callable[[mujoco.MjModel, mujoco.MjData], None]

_RAW_CALLBACK = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p)
_active: StepHook | None = None  # the hook installed in this process (one episode at a time)
_TIME_SLACK = 1e-9  # s: a period's boundary reached up to rounding counts as reached


@dataclass(frozen=True)
class PeriodicCallback:
    """`callback(model, data)` once per `period` seconds of simulated time, first at the episode's start."""

    period: float
    callback: StepCallback


class StepHook:
    """While entered, calls each PeriodicCallback on the episode's (model, data) as `mj_step` reaches
    its next period; another hook's or a user's control callback is restored on exit.

    The first exception a callback raises ends the callbacks and is raised by the episode's next
    step (`error` keeps it, for a caller that catches it)."""

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, callbacks: Sequence[PeriodicCallback]):
        for entry in callbacks:
            if not entry.period > 0.0:
                raise ValueError(f"a step callback's period must be positive, got {entry.period!r}")
        self.model = model
        self.data = data
        self.callbacks = tuple(callbacks)
        self.error: BaseException | None = None
        self.pending: BaseException | None = None
        self._address = data._address
        self._due = [float(data.time)] * len(self.callbacks)
        self._next_due = min(self._due, default=float("inf"))  # the earliest of them
        self._raw = _RAW_CALLBACK(self._on_control)  # kept alive while installed
        self._previous = None

    def _on_control(self, _model_address: int | None, data_address: int | None) -> None:
        # Called at every step of every model in the process: the common cases return first.
        if data_address != self._address or self.data.time + _TIME_SLACK < self._next_due:
            return
        if self.pending is None:
            try:
                self.run_due()
            except BaseException as error:  # noqa: BLE001 - nothing may unwind through MuJoCo's C frames
                self.error = error
                self.stop(error)
        if self.pending is not None:  # also set by a signal handler that ran in this frame
            mujoco.set_mjcb_control(self._raise_pending)

    def _raise_pending(self, _model: mujoco.MjModel, data: mujoco.MjData) -> None:
        if data is self.data and self.pending is not None:
            error, self.pending = self.pending, None
            mujoco.set_mjcb_control(self._raw)
            raise error

    def run_due(self) -> None:
        """Run the callbacks whose time has come at `data.time` (also callable directly, e.g. at the start)."""
        now = float(self.data.time)
        for k, entry in enumerate(self.callbacks):
            if now + _TIME_SLACK >= self._due[k]:
                entry.callback(self.model, self.data)
                # the next boundary after now: a controller that jumps time skips the missed ones
                missed = int((now + _TIME_SLACK - self._due[k]) // entry.period)
                self._due[k] += (missed + 1) * entry.period
        self._next_due = min(self._due, default=float("inf"))

    def stop(self, error: BaseException) -> None:
        """End the episode: the episode's next `mj_step` raises `error` (the first one asked for wins)."""
        if self.pending is None:
            self.pending = error
            if mujoco.get_mjcb_control() is self._raw:
                mujoco.set_mjcb_control(self._raise_pending)

    def __enter__(self) -> StepHook:
        global _active
        self._previous = mujoco.get_mjcb_control()
        mujoco.set_mjcb_control(self._raw)
        _active = self
        return self

    def __exit__(self, *exc) -> None:
        global _active
        mujoco.set_mjcb_control(self._previous)
        self._previous = None
        _active = None


_HOOK_CODE = StepHook._on_control.__code__


def raise_from_signal(error: BaseException, frame) -> None:
    """Raise `error` from a signal handler, or, when Python runs the handler inside a hook's ctypes
    callback (where ctypes would drop it), have that hook raise it at the episode's next step."""
    if _active is not None and frame is not None and frame.f_code is _HOOK_CODE:
        _active.stop(error)
        return
    raise error
