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
"""

from __future__ import annotations

import ctypes
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import mujoco

StepCallback = Callable[[mujoco.MjModel, mujoco.MjData], None]

_RAW_CALLBACK = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p)
_TIME_SLACK = 1e-9  # s: a period's boundary reached up to rounding counts as reached


@dataclass(frozen=True)
class PeriodicCallback:
    """`callback(model, data)` once per `period` seconds of simulated time, first at the episode's start."""

    period: float
    callback: StepCallback


class StepHook:
    """While entered, calls each PeriodicCallback on the episode's (model, data) as `mj_step` reaches
    its next period; another hook's or a user's control callback is restored on exit.

    A callback's exception cannot cross MuJoCo's C frames: the first one is kept in `error` and
    no callback runs after it (the harness reports it when the controller returns)."""

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, callbacks: Sequence[PeriodicCallback]):
        for entry in callbacks:
            if not entry.period > 0.0:
                raise ValueError(f"a step callback's period must be positive, got {entry.period!r}")
        self.model = model
        self.data = data
        self.callbacks = tuple(callbacks)
        self.error: BaseException | None = None
        self._address = data._address
        self._due = [float(data.time)] * len(self.callbacks)
        self._raw = _RAW_CALLBACK(self._on_control)  # kept alive while installed
        self._previous = None

    def _on_control(self, _model_address: int | None, data_address: int | None) -> None:
        if data_address != self._address or self.error is not None:
            return
        try:
            self.run_due()
        except BaseException as error:  # noqa: BLE001 - nothing may unwind through MuJoCo's C frames
            self.error = error

    def run_due(self) -> None:
        """Run the callbacks whose time has come at `data.time` (also callable directly, e.g. at the start)."""
        now = float(self.data.time)
        for k, entry in enumerate(self.callbacks):
            if now + _TIME_SLACK >= self._due[k]:
                entry.callback(self.model, self.data)
                # the next boundary after now: a controller that jumps time skips the missed ones
                missed = int((now + _TIME_SLACK - self._due[k]) // entry.period)
                self._due[k] += (missed + 1) * entry.period

    def __enter__(self) -> StepHook:
        self._previous = mujoco.get_mjcb_control()
        mujoco.set_mjcb_control(self._raw)
        return self

    def __exit__(self, *exc) -> None:
        mujoco.set_mjcb_control(self._previous)
        self._previous = None
