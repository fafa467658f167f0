"""Images from a spec's camera objects for `prsc.SceneEnv` (docs/learning.md, "Observations").

A camera object of the spec is a MuJoCo camera named after the object, with the object's
resolution (backends/mjcf.py). `CameraViews` renders the cameras an observation asks for,
each channel ("rgb", "depth", "segmentation") as `mujoco.Renderer` gives it, with one
renderer per image size, kept for the environment's life.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np
from gymnasium import spaces

CHANNELS = ("rgb", "depth", "segmentation")


@dataclass(frozen=True)
class CameraView:
    """One camera of the observation: its name, image size and the channels it gives."""

    name: str
    width: int
    height: int
    channels: tuple[str, ...]

    def space(self) -> spaces.Dict:
        """The Gymnasium space of this camera's channels."""
        shape = (self.height, self.width)
        boxes = {
            "rgb": spaces.Box(0, 255, shape + (3,), dtype=np.uint8),
            "depth": spaces.Box(0.0, np.inf, shape, dtype=np.float32),
            # (object id, object type) per pixel, -1 where nothing is drawn (mujoco.Renderer).
            "segmentation": spaces.Box(-1, np.iinfo(np.int32).max, shape + (2,), dtype=np.int32),
        }
        return spaces.Dict({channel: boxes[channel] for channel in self.channels})


def camera_views(model, asked: str | Mapping[str, str | Sequence[str]]) -> tuple[CameraView, ...]:
    """The cameras an observation asks for: "cameras" (every camera object, RGB) or
    {camera name: channel or channels}; a ValueError names an unknown camera or channel."""
    import mujoco

    names = [model.camera(c).name for c in range(model.ncam)]
    if asked == "cameras":
        if not names:
            raise ValueError('observation="cameras": this spec has no camera object (a Camera of the model library)')
        asked = {name: ("rgb",) for name in names}
    if not isinstance(asked, Mapping) or not asked:
        raise ValueError('observation must be a function, "cameras", or {camera name: channels}')
    views = []
    for name, channels in asked.items():
        if name not in names:
            raise ValueError(f"observation: no camera {name!r} in this spec (its cameras: {', '.join(names) or 'none'})")
        chosen = (channels,) if isinstance(channels, str) else tuple(channels)
        unknown = [c for c in chosen if c not in CHANNELS]
        if unknown or not chosen:
            raise ValueError(f"observation: camera {name!r} channels must be among {', '.join(CHANNELS)}, got {list(chosen)}")
        width, height = (int(v) for v in model.cam_resolution[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, name)])
        views.append(CameraView(name, width, height, chosen))
    return tuple(views)


class Renderers:
    """One `mujoco.Renderer` per image size for a model, made when first asked for; its render
    context made again when the model's context inputs changed, and given the numbers derived
    from stat.extent in place when only those did (a reset's new stat.extent)."""

    def __init__(self, model) -> None:
        self.model = model
        self._by_size: dict[tuple[int, int], Any] = {}
        self._made_at: dict[tuple[int, int], tuple] = {}  # (context inputs, patch) each renderer's context has
        self.remade = 0  # render contexts made again since the renderers were made
        self.patched = 0  # render contexts given another extent's numbers in place

    def get(self, height: int, width: int):
        """The renderer of this size, rendering what a fresh renderer of the model as it is now renders."""
        import mujoco

        from prsc.runner.rendering import context_inputs, context_patch, patch_context

        size = (height, width)
        state = (context_inputs(self.model), context_patch(self.model))
        renderer = self._by_size.get(size)
        if renderer is None:
            renderer = self._by_size[size] = mujoco.Renderer(self.model, height, width)
        elif self._made_at[size][0] != state[0]:
            renderer = self._by_size[size] = _remade(renderer, self.model, height, width)
            self.remade += 1
        elif self._made_at[size][1] != state[1]:
            gl, context = getattr(renderer, "_gl_context", None), getattr(renderer, "_mjr_context", None)
            if isinstance(context, mujoco.MjrContext) and gl is not None:
                gl.make_current()
                patch_context(context, state[1])
                self.patched += 1
            else:  # not the renderer's parts we know: a new renderer
                renderer = self._by_size[size] = _remade(renderer, self.model, height, width)
                self.remade += 1
        self._made_at[size] = state
        return renderer

    def render(self, data, camera: Any, height: int, width: int, channel: str = "rgb") -> np.ndarray:
        """One channel of the image from `camera` (a name, an id, or -1 / an MjvCamera for the free camera)."""
        renderer = self.get(height, width)
        renderer.update_scene(data, camera)
        if channel == "rgb":
            return renderer.render()
        if channel == "depth":
            renderer.enable_depth_rendering()
        else:
            renderer.enable_segmentation_rendering()
        try:
            return renderer.render()
        finally:
            renderer.disable_depth_rendering()
            renderer.disable_segmentation_rendering()

    def observe(self, views: tuple[CameraView, ...], data) -> dict[str, dict[str, np.ndarray]]:
        """Every view's channels, as the observation space holds them."""
        return {v.name: {c: self.render(data, v.name, v.height, v.width, c) for c in v.channels} for v in views}

    def close(self) -> None:
        """Free every renderer."""
        for renderer in self._by_size.values():
            renderer.close()
        self._by_size.clear()
        self._made_at.clear()


def _remade(renderer, model, height: int, width: int):
    """`renderer` with a new render context for `model` in its own GL context, as mujoco.Renderer's
    constructor makes one (0.13 CPU s for Table-Cube against 0.22 for a new renderer with its GL
    context, docs/learning.md); a new renderer where the renderer's parts are not as expected."""
    import mujoco

    gl, context = getattr(renderer, "_gl_context", None), getattr(renderer, "_mjr_context", None)
    if not isinstance(context, mujoco.MjrContext) or gl is None:
        renderer.close()
        return mujoco.Renderer(model, height, width)
    gl.make_current()
    context.free()
    renderer._mjr_context = context = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150.value)
    mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, context)
    context.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
    return renderer
