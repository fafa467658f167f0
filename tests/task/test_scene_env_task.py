"""prsc.SceneEnv with a task: terminated on success, truncated at `terminate after`, sparse and dense
rewards, info["is_success"] and info["task"]; user functions override; Gymnasium's checker passes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from gymnasium.utils.env_checker import check_env

from prsc.scene_env import SceneEnv

SPEC = Path(__file__).with_name("tray_task.prs")


def test_an_env_with_a_task_is_truncated_at_its_time_limit_with_the_task_in_info():
    env = SceneEnv(SPEC, frame_skip=50)
    _, info = env.reset(seed=0)
    assert info["task"]["outcome"] is None and not info["is_success"]
    steps, truncated, terminated = 0, False, False
    while not (truncated or terminated):
        _, reward, terminated, truncated, info = env.step(np.zeros(env.action_space.shape))
        steps += 1
        assert reward == 0.0
    assert truncated and not terminated and info["task"]["outcome"] == "timeout"
    assert steps == 30  # terminate after 3 seconds, 0.1 s a step
    assert set(info["task"]["robustness"]) == {"goal", "fail:dropped"} and info["task"]["robustness"]["goal"] < 0
    env.close()


def test_dense_reward_is_the_goal_robustness_and_a_user_function_overrides():
    env = SceneEnv(SPEC, frame_skip=50, reward="dense")
    env.reset(seed=0)
    _, reward, _, _, info = env.step(np.zeros(env.action_space.shape))
    assert reward == info["task"]["goal_robustness"] < 0
    env = SceneEnv(SPEC, frame_skip=50, reward=lambda s, m, d: 7.0, terminated=lambda s, m, d: True)
    env.reset(seed=0)
    _, reward, terminated, _, _ = env.step(np.zeros(env.action_space.shape))
    assert reward == 7.0 and terminated


def test_gymnasium_checks_the_env_with_a_task():
    check_env(SceneEnv(SPEC, frame_skip=50), skip_render_check=True)


def test_the_env_terminates_with_reward_1_when_the_cube_rests_in_the_tray():
    import mujoco

    from tests.task.test_mujoco_task import tray_floor_point

    env = SceneEnv(SPEC, frame_skip=10)
    env.reset(seed=0)
    cube = mujoco.mj_name2id(env.model, mujoco.mjtObj.mjOBJ_BODY, "cube")
    address = env.model.jnt_qposadr[env.model.body_jntadr[cube]]
    env.data.qpos[address:address + 3] = tray_floor_point(env.scene) + [0, 0, 0.01]
    rewards = []
    for _ in range(100):
        _, reward, terminated, truncated, info = env.step(np.zeros(env.action_space.shape))
        rewards.append(reward)
        if terminated:
            break
    assert terminated and not truncated and info["is_success"] and rewards[-1] == 1.0 and sum(rewards) == 1.0
