"""Success only when it holds, in MuJoCo: scripted cube trajectories watched by the TaskMonitor
through the episode's StepHook, as `prsc run` watches them."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

import prsc
from prsc.runner.step_hook import PeriodicCallback, StepHook
from prsc.runner.task_monitor import CONTROL_PERIOD, TaskMonitor

SPEC = Path(__file__).with_name("tray_task.prs")


@pytest.fixture(scope="module")
def scene_and_model():
    scenario = prsc.load(SPEC)
    scene = scenario.scene(0, 0)
    return scene, scenario.model(0, 0)


def tray_floor_point(scene: dict) -> np.ndarray:
    """Where the cube's centre is when it rests on the tray's floor (from the compiled task)."""
    task = scene["task"]
    tray = next(o for o in task["objects"] if o["name"] == "tray")
    cube = next(o for o in task["objects"] if o["name"] == "cube")
    position = np.array(next(o for o in scene["objects"] if o["name"] == "tray")["position"])
    return position + [0, 0, tray["support"]["high"] + cube["dimensions"][2] / 2 + 0.0005]


def run_script(scene, model, script, seconds: float) -> dict:
    """Step `seconds` of simulated time, `script(data)` before each step placing the cube (or not),
    watched twice: each control step evaluated as it happens (`update`, what a recorder reads), and
    logged then evaluated together (`log`, what `prsc run` does). Both records must be the same."""
    results = []
    for watch in ("update", "log"):
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        monitor = TaskMonitor(scene, model)
        cube = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "cube")
        qpos = model.jnt_qposadr[model.body_jntadr[cube]]
        dof = model.jnt_dofadr[model.body_jntadr[cube]]
        with StepHook(model, data, [PeriodicCallback(CONTROL_PERIOD, getattr(monitor, watch))]):
            while data.time < seconds:
                target = script(data.time)
                if target is not None:
                    data.qpos[qpos:qpos + 3] = target
                    data.qpos[qpos + 3:qpos + 7] = [1, 0, 0, 0]
                    data.qvel[dof:dof + 6] = 0
                mujoco.mj_step(model, data)
        results.append(monitor.result(model, data, controller_finished=True))
    assert results[0] == results[1]
    return results[0]


def test_a_cube_carried_5_cm_above_the_tray_is_no_success(scene_and_model):
    scene, model = scene_and_model
    above = tray_floor_point(scene) + [0, 0, 0.05]
    result = run_script(scene, model, lambda t: above, 1.5)
    assert result["outcome"] == "incomplete" and result["robustness"]["goal"] < 0
    assert result["records"]["inside"] is False


def test_a_cube_that_drops_in_and_bounces_out_is_no_success(scene_and_model):
    scene, model = scene_and_model
    inside = tray_floor_point(scene)
    outside = inside + [-0.25, 0, 0]
    result = run_script(scene, model, lambda t: inside if 0.3 < t < 0.6 else outside if t >= 0.6 else inside + [0, 0, 0.1], 1.5)
    assert result["outcome"] == "incomplete" and not result["trivial"]
    assert result["robustness"]["goal"] <= 0


def test_a_cube_resting_in_the_tray_for_half_a_second_is_a_success(scene_and_model):
    scene, model = scene_and_model
    inside = tray_floor_point(scene)
    result = run_script(scene, model, lambda t: inside + [0, 0, 0.03] if t < 0.1 else None, 1.5)
    assert result["outcome"] == "success" and 0.6 <= result["decided_at"] < 1.2
    assert result["robustness"]["goal"] > 0 and result["robustness"]["fail:dropped"] > 0
    assert result["records"]["inside"] is True and len(result["records"]["start"]) == 3


def test_a_cube_resting_in_the_tray_from_the_start_is_trivial(scene_and_model):
    scene, model = scene_and_model
    inside = tray_floor_point(scene) - [0, 0, 0.0006]  # in contact with the floor at the first step
    result = run_script(scene, model, lambda t: inside if t < 0.001 else None, 1.0)
    assert result["trivial"] and result["outcome"] == "success"


def test_a_dropped_cube_fails_and_the_time_limit_ends_as_timeout(scene_and_model):
    scene, model = scene_and_model
    below = tray_floor_point(scene) + [0, 0.6, -0.3]
    result = run_script(scene, model, lambda t: below if t > 0.2 else None, 0.5)
    assert result["outcome"] == "fail:dropped" and result["robustness"]["fail:dropped"] < 0
    result = run_script(scene, model, lambda t: None, 3.1)
    assert result["outcome"] == "timeout" and result["decided_at"] == pytest.approx(3.0, abs=0.03)
