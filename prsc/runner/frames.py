"""Frame strips of episodes: an overview camera rendered at the controller's key moments."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from prsc.backends.names import with_body_names

from prsc.runner.harness import run_episode
from prsc.runner.rendering import OffscreenRenderer
from prsc.runner.episode_records import EpisodeResult, EpisodeTask

FRAMES_WITHOUT_SNAPSHOTS = 8  # a controller that names no moments gets frames evenly spaced in time

FRAME_WIDTH = 480
FRAME_HEIGHT = 360


class FrameRecorder:
    """Observer for `run_episode`: renders an oblique overview of the scene at each moment."""

    def __init__(self, scene: dict):
        self.scene = scene
        self.frames: list[tuple[str, float, np.ndarray]] = []
        self._renderer: OffscreenRenderer | None = None
        self._camera = mujoco.MjvCamera()
        self._ceiling = -1  # the scene's camera object, found in _setup

    def _setup(self, model: mujoco.MjModel) -> None:
        """Create the renderer and aim the free camera at the middle of the non-camera objects."""
        self._renderer = OffscreenRenderer(model, FRAME_WIDTH, FRAME_HEIGHT)
        points = np.array([o["position"] for o in self.scene["objects"]
                           if o.get("camera") is None and o.get("class") != "Camera"]
                          or [o["position"] for o in self.scene["objects"]] or [[0.0, 0.0, 0.0]])
        lo, hi = points.min(axis=0), points.max(axis=0)
        self._camera.type = mujoco.mjtCamera.mjCAMERA_FREE
        self._camera.lookat[:] = (lo + hi) / 2
        self._camera.distance = max(1.0, 1.25 * float(np.linalg.norm(hi[:2] - lo[:2])))
        # From the robots' front (+y side) looking back at them: the left robot appears on the right.
        self._camera.azimuth = -90.0
        self._camera.elevation = -50.0
        name = next((o["body"] for o in with_body_names(self.scene)["objects"] if o.get("camera") is not None), None)
        if name is not None:
            self._ceiling = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, name)

    def __call__(self, label: str, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Render the overview (and, when the controller perceives, the ceiling camera's view)."""
        if self._renderer is None:
            self._setup(model)
        if self.frames and self.frames[-1][1] == float(data.time) and not label.startswith("perceive"):
            last_label, t, image = self.frames[-1]
            self.frames[-1] = (f"{last_label}; {label}", t, image)  # nothing moved since
            return
        self.frames.append((label, float(data.time), self._renderer.rgb(data, self._camera)))
        if label.startswith("perceive"):
            self.frames.append(("ceiling camera view", float(data.time), self._renderer.rgb(data, self._ceiling)))

    def close(self) -> None:
        """Release the model's render context."""
        if self._renderer is not None:
            self._renderer.close()


def record_episode(task: EpisodeTask, sim_seconds: float) -> tuple[EpisodeResult, list]:
    """Re-run an episode (deterministic) while recording frames: at the moments the controller
    names (`snapshot`), or evenly over its `sim_seconds` when it names none."""
    named = FrameRecorder(task.scene)
    timed = FrameRecorder(task.scene)
    every = max(sim_seconds, 1e-3) / FRAMES_WITHOUT_SNAPSHOTS

    def observe(label: str, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        if not label.startswith("t = "):
            named(label, model, data)
        elif not named.frames:  # once the controller names a moment, the timed frames are not shown
            timed(label, model, data)

    try:
        result = run_episode(task, observer=observe, frame_every=every)
    finally:
        named.close()
        timed.close()
    return result, named.frames or timed.frames


def write_strip(frames: list[tuple[str, float, np.ndarray]], title: str, path: Path, columns: int = 4) -> Path:
    """Write frames as one labelled PNG grid."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = max(1, -(-len(frames) // columns))
    fig, axes = plt.subplots(rows, columns, figsize=(4.0 * columns, 3.1 * rows + 0.5), squeeze=False)
    for ax in axes.flat:
        ax.axis("off")
    for ax, (label, t, image) in zip(axes.flat, frames):
        ax.imshow(image)
        ax.set_title(f"{t:.1f} s  {label}", fontsize=8)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp.png")
    fig.savefig(tmp, dpi=80)
    plt.close(fig)
    tmp.replace(path)
    return path
