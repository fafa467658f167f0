"""`prsc.RecordEpisodes`: a Gymnasium wrapper that records the episodes of a `prsc.SceneEnv`
driven by a user's own policy into a LeRobot v3 or robomimic dataset, in the files
`prsc run --record` writes (docs/datasets.md).

    env = prsc.RecordEpisodes(prsc.SceneEnv("spec.prs", render_mode="rgb_array"), "out/demos", format="lerobot")
    obs, info = env.reset(seed=0)
    ... env.step(policy(obs)) ...
    env.close()                      # the last episode is committed

A frame per `step`: the state before it, the action sent, and the step's reward as
`next.reward`, `terminated or truncated` as `next.done` (and on an episode's last frame) and
`info["is_success"]` (when the env gives it) as `next.success`. An episode is committed when
the next `reset` or `close` comes; the folder is a finished dataset after each.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path
from typing import Any

import gymnasium
import numpy as np


class RecordEpisodes(gymnasium.Wrapper):
    """Records every episode of a SceneEnv (a frame per step) into the dataset folder `root`."""

    def __init__(self, env: gymnasium.Env, root: str | os.PathLike[str], format: str = "lerobot", *,
                 keep: str = "all", images: bool = True, lossless: bool = False, task: str | None = None) -> None:
        super().__init__(env)
        import mujoco

        from prsc.runner.demo_dataset import DemoDataset
        from prsc.runner.episode_records import RecordSettings

        base = env.unwrapped
        if not hasattr(base, "spec_path") or not hasattr(base, "frame_skip"):
            raise TypeError(f"RecordEpisodes records a prsc.SceneEnv, not {type(base).__name__}")
        if images and not os.environ.get("MUJOCO_GL"):
            raise RuntimeError("RecordEpisodes renders the spec's cameras offscreen: create the SceneEnv with "
                               "render_mode='rgb_array' (it chooses a headless GL backend) or set MUJOCO_GL, "
                               "or pass images=False")
        rate = 1.0 / (base.frame_skip * base.model.opt.timestep)
        if abs(rate - round(rate)) > 1e-6:
            raise ValueError(f"a frame per step is {rate:g} frames per simulated second; LeRobot needs a whole "
                             "number: choose frame_skip so that frame_skip * timestep divides 1 s")
        self.settings = RecordSettings(format, int(round(rate)), lossless=lossless, images=images, task=task or "")
        key = {"command": "RecordEpisodes", "spec": str(base.spec_path),
               "spec_sha256": hashlib.sha256(Path(base.spec_path).read_bytes()).hexdigest(), "format": format, "fps": self.settings.fps,
               "images": images, "lossless": lossless, "frame_skip": base.frame_skip}
        env_args = {"env_name": "prsc/SceneEnv-v0", "type": 2, "env_kwargs": {
            "spec": key["spec"], "frame_skip": base.frame_skip}}
        self.dataset = DemoDataset(Path(root), key, keep, env_args).open()
        self._mujoco = mujoco
        self._recorder = None
        self._model_binary: bytes | None = None
        self._next = self.dataset.processed  # the number the next episode takes in the dataset

    def reset(self, **kwargs: Any):
        """Commit the episode so far; start recording the next scene's."""
        self._finish()
        observation, info = self.env.reset(**kwargs)
        from prsc.runner.demo_frames import DemoRecorder

        base = self.env.unwrapped
        self._recorder = DemoRecorder(base.scene, self.settings.fps, images=self.settings.images)
        model = base.model
        buffer = np.empty(self._mujoco.mj_sizeModel(model), dtype=np.uint8)
        self._mujoco.mj_saveModel(model, None, buffer)  # after the reset: the model of this scene
        self._model_binary = buffer.tobytes()
        self._scratch = self._mujoco.MjData(model)
        return observation, info

    def step(self, action):
        """Record the state and the action, then step; the step's reward and end go with the frame."""
        if self._recorder is None:
            return self.env.step(action)
        from prsc.runner.demo_frames import STATE_SPEC

        base = self.env.unwrapped
        mujoco = self._mujoco
        # The frame: the state before the step, forward-computed on a copy (after mj_step the
        # positions in `data` are those before its integration), with the action as its controls.
        state = np.empty(mujoco.mj_stateSize(base.model, STATE_SPEC))
        mujoco.mj_getState(base.model, base.data, state, STATE_SPEC)
        mujoco.mj_setState(base.model, self._scratch, state, STATE_SPEC)
        self._scratch.ctrl[:] = np.asarray(action, dtype=np.float64)  # what SceneEnv.step sets
        mujoco.mj_forward(base.model, self._scratch)
        self._recorder.capture(base.model, self._scratch)
        observation, reward, terminated, truncated, info = self.env.step(action)
        frames = self._recorder.frames
        if frames.values is None:
            frames.values = []
        frames.values.append((float(reward), bool(terminated or truncated), bool(info.get("is_success", False))))
        return observation, reward, terminated, truncated, info

    def _finish(self) -> None:
        recorder, self._recorder = self._recorder, None
        if recorder is None:
            return
        recorder.close()
        frames = recorder.frames
        if frames is None or not len(frames):
            return
        reward, _, success = frames.values[-1]
        frames.values[-1] = (reward, True, success)  # the episode ends at its last frame
        from prsc.runner.episode_encoding import encode_episode

        scene = recorder.scene
        outcome = "success" if any(v[2] for v in frames.values) else "ended"
        result = {"index": self._next, "seed": int(scene.get("seed", 0)), "outcome": outcome, "reason": "",
                  "sim_seconds": round(float(frames.times[-1]), 3)}
        episode = encode_episode(frames, self.settings, scene, result, model_binary=self._model_binary)
        self.dataset.add(episode, self._next)
        self._next += 1

    def close(self) -> None:
        """Commit the last episode, release the dataset folder, close the env."""
        try:
            self._finish()
        finally:
            self.dataset.close()
            self.env.close()
