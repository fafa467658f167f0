"""`prsc.SceneEnv`: a Gymnasium environment whose every reset is a new scene of a spec,
written into one MuJoCo model without recompiling (docs/learning.md). Needs the [gym] extra.

- `reset(seed=s)` draws scene 0 of seed s; each later `reset()` the next scene of that seed
  (seed 0 when no seed was ever given), so a run is reproducible scene by scene; when the spec's
  sampler batches, scenes are drawn `draw_ahead` at a time after a seeded reset, each later draw
  twice the last up to `draw_ahead_max` (a seeded reset stays cheap, and the steady rate is that
  of large batches; scene k is the same; a `draw_ahead_max` below `draw_ahead` keeps it fixed);
- `step(action)` sets `data.ctrl` and steps MuJoCo `frame_skip` times; the action space is
  bounded (`action_bounds`); `max_episode_steps` steps give `truncated`;
- the observation is `qpos` and `qvel` by default; `observation="cameras"` gives every camera
  object's RGB image, `{camera: channels}` chosen cameras' "rgb", "depth", "segmentation"
  (prsc/scene_cameras.py); or a function `observation(scene, model, data)` with its
  `observation_space`; reward and termination are user functions of (scene, model, data),
  0 and False when not given;
- `render()` draws the free camera, or the spec camera `render_camera`, with
  `mujoco.Renderer` (render_mode "rgb_array"; headless: with MUJOCO_GL unset, the first of
  EGL and OSMesa that works, chosen before mujoco is imported);
- `info["scene"]` is the scene JSON of the episode, given by `reset` only (a step's info is
  empty: a step costs MuJoCo's steps and little more).
- with a task in the spec (docs/tasks.md): `terminated` when the goal is reached or a failure
  holds, `truncated` at `terminate after`, `info["is_success"]` and `info["task"]` (status and
  each statement's robustness), reward 1 on success (`reward="sparse"`, the default) or the
  goal's robustness (`reward="dense"`); user functions still override.
"""

from __future__ import annotations

import os
import pickle
from typing import Any, Callable, Mapping, Sequence

import gymnasium
import numpy as np
from gymnasium import spaces

from prsc.scenario import RESET_DRAW_AHEAD, RESET_DRAW_AHEAD_MAX

SceneFunction = Callable[[dict, Any, Any], Any]
UNBOUNDED_ACTUATOR_BOUND = 1.0
"""The action bound of an actuator with neither a control range nor a limited joint it holds
as a position servo (a motor without `ctrlrange`): [-1, 1]."""


def action_bounds(model) -> tuple[np.ndarray, np.ndarray]:
    """Per actuator: its control range when limited, else the limits of the joint it holds as a
    position servo, else +-UNBOUNDED_ACTUATOR_BOUND (docs/learning.md, "Actions")."""
    import mujoco

    from prsc.user_assets.joint_servos import is_position_servo

    low = np.full(model.nu, -UNBOUNDED_ACTUATOR_BOUND)
    high = np.full(model.nu, UNBOUNDED_ACTUATOR_BOUND)
    for a in range(model.nu):
        joint = model.actuator_trnid[a, 0]
        if model.actuator_ctrllimited[a]:
            low[a], high[a] = model.actuator_ctrlrange[a]
        elif (model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT and model.jnt_limited[joint]
              and is_position_servo(model, a)):
            low[a], high[a] = model.jnt_range[joint]
    return low, high


class SceneEnv(gymnasium.Env):
    """A MuJoCo environment over the scenes of a .prs spec (a reset is `scenario.apply`)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 30}

    def __init__(
        self,
        spec: str | os.PathLike[str],
        *,
        frame_skip: int = 10,
        observation: SceneFunction | str | Mapping[str, str | Sequence[str]] | None = None,
        observation_space: spaces.Space | None = None,
        reward: SceneFunction | str | None = None,
        terminated: SceneFunction | None = None,
        max_episode_steps: int | None = None,
        render_mode: str | None = None,
        render_camera: str | None = None,
        width: int = 640,
        height: int = 480,
        draw_ahead: int = RESET_DRAW_AHEAD,
        draw_ahead_max: int = RESET_DRAW_AHEAD_MAX,
        include_dirs: Sequence[str | os.PathLike[str]] = (),
    ) -> None:
        cameras = observation is not None and not callable(observation)
        if render_mode == "rgb_array" or cameras:
            from prsc.runner.gl import choose_gl_backend

            choose_gl_backend()  # headless rendering: MuJoCo reads MUJOCO_GL when first imported
        import mujoco

        from prsc.runner.task_steps import TaskSteps
        from prsc.scenario import load
        from prsc.scene_cameras import Renderers, camera_views

        if frame_skip < 1:
            raise ValueError(f"frame_skip must be >= 1, got {frame_skip}")
        if max_episode_steps is not None and max_episode_steps < 1:
            raise ValueError(f"max_episode_steps must be >= 1 or None, got {max_episode_steps}")
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        if callable(observation) and observation_space is None:
            raise ValueError("an observation function needs its observation_space")
        self.scenario = load(spec, include_dirs)
        self.spec_path = os.fspath(spec)
        self.model = self.scenario.model()
        self.data = mujoco.MjData(self.model)
        self.frame_skip = frame_skip
        self.max_episode_steps = max_episode_steps
        self.render_mode = render_mode
        self._observe = observation if callable(observation) else None
        self._reward = reward if callable(reward) else None
        self._terminated = terminated
        if isinstance(reward, str) and not self.scenario.program.task:
            raise ValueError(f"reward={reward!r} reads the spec's task, and {spec} states none (docs/tasks.md)")
        self._task = TaskSteps(reward if isinstance(reward, str) else "sparse") if self.scenario.program.task else None
        self._size = (height, width)
        self._renderers = Renderers(self.model)
        self._views = camera_views(self.model, observation) if cameras else ()
        if render_camera is not None:
            camera_views(self.model, {render_camera: "rgb"})  # an unknown name is an error now, not at render()
        self._render_camera = -1 if render_camera is None else render_camera
        self._seed = 0
        self._next_index = 0
        if draw_ahead < 1:
            raise ValueError(f"draw_ahead must be >= 1, got {draw_ahead}")
        self._draw_ahead = (draw_ahead, draw_ahead_max)
        self._draw = self.scenario.drawer(self._seed, *self._draw_ahead)
        self._steps = 0
        self.scene: dict[str, Any] = {}
        # Actions are clipped to the bounds in float64 (the space's float32 bounds may round outwards).
        self._low, self._high = action_bounds(self.model)
        self.action_space = spaces.Box(self._low.astype(np.float32), self._high.astype(np.float32), dtype=np.float32)
        if self._views:
            self.observation_space = spaces.Dict({v.name: v.space() for v in self._views})
        else:
            size = self.model.nq + self.model.nv
            self.observation_space = observation_space or spaces.Box(-np.inf, np.inf, (size,), dtype=np.float64)

    def _observation(self) -> Any:
        if self._observe is not None:
            return self._observe(self.scene, self.model, self.data)
        if self._views:
            return self._renderers.observe(self._views, self.data)
        return np.concatenate([self.data.qpos, self.data.qvel])

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Start an episode on the next scene of the seed (scene 0 of `seed` when one is given)."""
        super().reset(seed=seed)
        if seed is not None:
            self._seed, self._next_index = int(seed), 0
            self._draw = self.scenario.drawer(self._seed, *self._draw_ahead)
        self.scene = self._draw(self._next_index)
        self._next_index += 1
        self._steps = 0
        self.scenario.apply(self.scene, self.model, self.data)
        info = self._task.reset(self.scene, self.model, self.data) if self._task else {}
        # A copy: a caller may keep or edit what it was given (Gymnasium's rule); once per episode. The scene
        # is JSON data: a pickle round trip copies it whole in a fifth of copy.deepcopy's time (86 against 398 us
        # on bin_ten_parts, as much as `apply` itself).
        copied = pickle.loads(pickle.dumps(self.scene, protocol=pickle.HIGHEST_PROTOCOL))
        return self._observation(), {"scene": copied, **info}

    def step(self, action):
        """Set the controls (clipped to the action space) and step MuJoCo `frame_skip` times."""
        import mujoco

        np.minimum(np.maximum(action, self._low), self._high, out=self.data.ctrl)  # np.clip costs twice as much
        mujoco.mj_step(self.model, self.data, nstep=self.frame_skip)
        self._steps += 1
        task = self._task.step(self.model, self.data) if self._task else None
        reward = float(self._reward(self.scene, self.model, self.data)) if self._reward else task.reward if task else 0.0
        done = bool(self._terminated(self.scene, self.model, self.data)) if self._terminated else bool(task and task.terminated)
        truncated = bool(task and task.truncated) or (self.max_episode_steps is not None and self._steps >= self.max_episode_steps)
        return self._observation(), reward, done, truncated, (task.info if task else {})

    def render(self):
        """The scene from the free camera, or the spec camera `render_camera`, as an RGB array (render_mode "rgb_array")."""
        if self.render_mode != "rgb_array":
            return None
        return self._renderers.render(self.data, self._render_camera, *self._size)

    def close(self) -> None:
        """Free the renderers."""
        self._renderers.close()


if "prsc/SceneEnv-v0" not in gymnasium.registry:
    # gymnasium.make("prsc/SceneEnv-v0", spec="specs/table_cube.prs") once prsc.scene_env is imported.
    gymnasium.register(id="prsc/SceneEnv-v0", entry_point="prsc.scene_env:SceneEnv")
