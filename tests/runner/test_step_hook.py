"""The per-step hook: it runs on the episode's own data only, at its period of simulated time,
while other models compile and step, and restores whatever control callback was there."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from prsc.runner.step_hook import PeriodicCallback, StepHook

BALL = "<mujoco><option timestep='0.002'/><worldbody><body pos='0 0 1'><freejoint/><geom size='.1'/></body></worldbody></mujoco>"


def _episode():
    model = mujoco.MjModel.from_xml_string(BALL)
    return model, mujoco.MjData(model)


def test_the_hook_sees_the_episode_at_its_period_while_other_models_compile_and_step():
    model, data = _episode()
    times, heights = [], []

    def watch(m, d):
        assert m is model and d is data
        times.append(round(float(d.time), 6))
        heights.append(float(d.qpos[2]))

    with StepHook(model, data, [PeriodicCallback(0.01, watch)]) as hook:
        for _ in range(10):
            mujoco.mj_step(model, data, nstep=5)  # 0.01 s per call
            other = mujoco.MjModel.from_xml_string(BALL)  # a controller's IK copy compiles...
            mujoco.mj_step(other, mujoco.MjData(other), nstep=7)  # ...and steps: never seen
    assert hook.error is None
    assert times == pytest.approx([0.01 * k for k in range(10)])
    assert heights[0] == 1.0 and all(np.diff(heights) < 0)  # falling, state of that very step


def test_a_callback_exception_is_raised_by_the_next_step_with_a_clean_state():
    model, data = _episode()
    calls = []

    def fails(m, d):
        calls.append(d.time)
        if len(calls) == 3:
            raise RuntimeError("monitor bug")

    with StepHook(model, data, [PeriodicCallback(0.002, fails)]) as hook:
        with pytest.raises(RuntimeError, match="monitor bug"):
            mujoco.mj_step(model, data, nstep=10)
    assert isinstance(hook.error, RuntimeError) and len(calls) == 3
    clean_model, clean = _episode()
    mujoco.mj_step(clean_model, clean, nstep=3)  # the raise comes before the 4th step integrates
    assert data.time == pytest.approx(clean.time) and np.array_equal(data.qpos, clean.qpos)


def test_a_signal_handler_that_runs_inside_the_hook_still_ends_the_episode():
    """SIGALRM's handler often runs inside the ctypes callback, where ctypes drops a raise:
    raise_from_signal delivers it at the episode's next step instead, every time."""
    import signal

    from prsc.runner.faults import SimulationTimeLimit
    from prsc.runner.step_hook import raise_from_signal

    def tick(signum, frame):
        raise_from_signal(SimulationTimeLimit(), frame)

    previous = signal.signal(signal.SIGALRM, tick)
    try:
        for _ in range(5):
            model, data = _episode()
            with StepHook(model, data, [PeriodicCallback(0.002, lambda m, d: sum(range(200)))]):
                signal.setitimer(signal.ITIMER_REAL, 0.005)
                with pytest.raises(SimulationTimeLimit):
                    for _ in range(10**6):
                        mujoco.mj_step(model, data, nstep=5)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def test_a_previous_control_callback_is_restored_and_periods_must_be_positive():
    model, data = _episode()
    with pytest.raises(ValueError, match="positive"):
        StepHook(model, data, [PeriodicCallback(0.0, lambda m, d: None)])
    assert mujoco.get_mjcb_control() is None
    with StepHook(model, data, [PeriodicCallback(0.01, lambda m, d: None)]):
        assert mujoco.get_mjcb_control() is not None
    assert mujoco.get_mjcb_control() is None
