"""Frame strips of episodes: an overview camera rendered at the controller's key moments."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from prsc.backends.runner.episode import EpisodeResult, run_episode

FRAME_WIDTH = 480
FRAME_HEIGHT = 360


class FrameRecorder:
    """Observer for `run_episode`: renders an oblique overview of the table at each moment."""

    def __init__(self, scene: dict):
        self.scene = scene
        self.frames: list[tuple[str, float, np.ndarray]] = []
        self._renderer: mujoco.Renderer | None = None
        self._camera = mujoco.MjvCamera()

    def _setup(self, model: mujoco.MjModel) -> None:
        """Create the renderer and aim the free camera at the middle of the non-camera objects."""
        self._renderer = mujoco.Renderer(model, height=FRAME_HEIGHT, width=FRAME_WIDTH)
        points = np.array([o["position"] for o in self.scene["objects"]
                           if o.get("camera") is None and o.get("class") != "Camera"])
        lo, hi = points.min(axis=0), points.max(axis=0)
        self._camera.type = mujoco.mjtCamera.mjCAMERA_FREE
        self._camera.lookat[:] = (lo + hi) / 2
        self._camera.distance = max(1.0, 1.25 * float(np.linalg.norm(hi[:2] - lo[:2])))
        # From the robots' front (+y side) looking back at them: the left robot appears on the right.
        self._camera.azimuth = -90.0
        self._camera.elevation = -50.0

    def __call__(self, label: str, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Render the overview (and, when the controller perceives, the ceiling camera's view)."""
        if self._renderer is None:
            self._setup(model)
        if self.frames and self.frames[-1][1] == float(data.time) and not label.startswith("perceive"):
            last_label, t, image = self.frames[-1]
            self.frames[-1] = (f"{last_label}; {label}", t, image)  # nothing moved since
            return
        self._renderer.update_scene(data, camera=self._camera)
        self.frames.append((label, float(data.time), self._renderer.render().copy()))
        if label.startswith("perceive"):
            camera = next(o["name"] for o in self.scene["objects"] if o.get("camera") is not None)
            self._renderer.update_scene(data, camera=camera)
            self.frames.append(("ceiling camera view", float(data.time), self._renderer.render().copy()))

    def close(self) -> None:
        """Release the GL context."""
        if self._renderer is not None:
            self._renderer.close()


def record_episode(scene: dict, mjcf_path: str | Path, seed: int | None = None) -> tuple[EpisodeResult, list]:
    """Re-run an episode (deterministic) while recording frames."""
    recorder = FrameRecorder(scene)
    try:
        result = run_episode(scene, mjcf_path, seed, observer=recorder)
    finally:
        recorder.close()
    return result, recorder.frames


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
