"""`prsc.SceneEnv`: a Gymnasium environment whose every reset is a new scene of a spec,
written into one MuJoCo model without recompiling (docs/learning.md). Needs the [gym] extra.

- `reset(seed=s)` draws scene 0 of seed s; each later `reset()` the next scene of that seed
  (seed 0 when no seed was ever given), so a run is reproducible scene by scene;
- `step(action)` sets `data.ctrl` (the actuators' control ranges are the action space) and
  steps MuJoCo `frame_skip` times;
- the observation is `qpos` and `qvel` by default, or `observation(scene, model, data)`
  with its `observation_space`; reward and termination are user functions of
  (scene, model, data), 0 and False when not given;
- `render()` draws the scene with `mujoco.Renderer` (render_mode "rgb_array"; headless: with
  MUJOCO_GL unset, the first of EGL and OSMesa that works, chosen before mujoco is imported);
- `info["scene"]` is the scene JSON of the episode.
"""

from __future__ import annotations

import copy
import os
from typing import Any, Callable, Sequence

import gymnasium
import numpy as np
from gymnasium import spaces

SceneFunction = Callable[[dict, Any, Any], Any]


class SceneEnv(gymnasium.Env):
    """A MuJoCo environment over the scenes of a .prs spec (a reset is `scenario.apply`)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 30}

    def __init__(
        self,
        spec: str | os.PathLike[str],
        *,
        frame_skip: int = 10,
        observation: SceneFunction | None = None,
        observation_space: spaces.Space | None = None,
        reward: SceneFunction | None = None,
        terminated: SceneFunction | None = None,
        render_mode: str | None = None,
        width: int = 640,
        height: int = 480,
        include_dirs: Sequence[str | os.PathLike[str]] = (),
    ) -> None:
        if render_mode == "rgb_array":
            from prsc.runner.gl import choose_gl_backend

            choose_gl_backend()  # headless rendering: MuJoCo reads MUJOCO_GL when first imported
        import mujoco

        from prsc.scenario import load

        if frame_skip < 1:
            raise ValueError(f"frame_skip must be >= 1, got {frame_skip}")
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        if observation is not None and observation_space is None:
            raise ValueError("an observation function needs its observation_space")
        self.scenario = load(spec, include_dirs)
        self.spec_path = os.fspath(spec)
        self.model = self.scenario.model()
        self.data = mujoco.MjData(self.model)
        self.frame_skip = frame_skip
        self.render_mode = render_mode
        self._observe = observation
        self._reward = reward
        self._terminated = terminated
        self._size = (height, width)
        self._renderer = None
        self._seed = 0
        self._next_index = 0
        self.scene: dict[str, Any] = {}
        limited = self.model.actuator_ctrllimited.astype(bool)
        low = np.where(limited, self.model.actuator_ctrlrange[:, 0], -np.inf)
        high = np.where(limited, self.model.actuator_ctrlrange[:, 1], np.inf)
        self.action_space = spaces.Box(low.astype(np.float32), high.astype(np.float32), dtype=np.float32)
        size = self.model.nq + self.model.nv
        self.observation_space = observation_space or spaces.Box(-np.inf, np.inf, (size,), dtype=np.float64)

    def _observation(self) -> Any:
        if self._observe is not None:
            return self._observe(self.scene, self.model, self.data)
        return np.concatenate([self.data.qpos, self.data.qvel]).astype(np.float64)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        """Start an episode on the next scene of the seed (scene 0 of `seed` when one is given)."""
        super().reset(seed=seed)
        if seed is not None:
            self._seed, self._next_index = int(seed), 0
        self.scene = self.scenario.scene(self._seed, self._next_index)
        self._next_index += 1
        self.scenario.apply(self.scene, self.model, self.data)
        return self._observation(), {"scene": copy.deepcopy(self.scene)}

    def step(self, action):
        """Set the controls and step MuJoCo `frame_skip` times."""
        import mujoco

        self.data.ctrl[:] = np.asarray(action, dtype=np.float64)
        mujoco.mj_step(self.model, self.data, nstep=self.frame_skip)
        reward = float(self._reward(self.scene, self.model, self.data)) if self._reward else 0.0
        done = bool(self._terminated(self.scene, self.model, self.data)) if self._terminated else False
        # A copy per call: a caller may keep or edit what it was given (Gymnasium's rule).
        return self._observation(), reward, done, False, {"scene": copy.deepcopy(self.scene)}

    def render(self):
        """The scene from MuJoCo's free camera as an RGB array (render_mode "rgb_array")."""
        if self.render_mode != "rgb_array":
            return None
        import mujoco

        if self._renderer is None:
            self._renderer = mujoco.Renderer(self.model, *self._size)
        self._renderer.update_scene(self.data)
        return self._renderer.render()

    def close(self) -> None:
        """Free the renderer."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None


if "prsc/SceneEnv-v0" not in gymnasium.registry:
    # gymnasium.make("prsc/SceneEnv-v0", spec="specs/table_cube.prs") once prsc.scene_env is imported.
    gymnasium.register(id="prsc/SceneEnv-v0", entry_point="prsc.scene_env:SceneEnv")
