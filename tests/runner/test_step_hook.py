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


def test_an_exception_is_kept_and_ends_the_callbacks_without_breaking_mujoco():
    model, data = _episode()
    calls = []

    def fails(m, d):
        calls.append(d.time)
        raise RuntimeError("monitor bug")

    with StepHook(model, data, [PeriodicCallback(0.002, fails)]) as hook:
        mujoco.mj_step(model, data, nstep=10)
    assert isinstance(hook.error, RuntimeError) and len(calls) == 1
    assert data.time == pytest.approx(0.02)


def test_a_previous_control_callback_is_restored_and_periods_must_be_positive():
    model, data = _episode()
    with pytest.raises(ValueError, match="positive"):
        StepHook(model, data, [PeriodicCallback(0.0, lambda m, d: None)])
    assert mujoco.get_mjcb_control() is None
    with StepHook(model, data, [PeriodicCallback(0.01, lambda m, d: None)]):
        assert mujoco.get_mjcb_control() is not None
    assert mujoco.get_mjcb_control() is None
