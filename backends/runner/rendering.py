"""Offscreen rendering of a model with the process's shared GL context (see gl.py)."""

from __future__ import annotations

import mujoco
import numpy as np

from prsc.backends.runner.faults import InfrastructureError
from prsc.backends.runner.gl import gl_context


class OffscreenRenderer:
    """RGB and metric depth images of one model at one size; a `mujoco.Renderer` without its own GL context.

    Only the model's MjrContext (meshes and textures on the GPU side) is made per model;
    the GL context is the process's."""

    def __init__(self, model: mujoco.MjModel, width: int, height: int):
        if width > model.vis.global_.offwidth or height > model.vis.global_.offheight:
            raise ValueError(f"image {width}x{height} exceeds the model's offscreen buffer "
                             f"{model.vis.global_.offwidth}x{model.vis.global_.offheight}")
        self.model = model
        self.width = width
        self.height = height
        gl_context()
        try:
            self._context = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150.value)
        except mujoco.FatalError as error:
            raise InfrastructureError(f"cannot make a MuJoCo render context: {error}") from None
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, self._context)
        self._context.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
        self._scene = mujoco.MjvScene(model=model, maxgeom=10000)
        self._option = mujoco.MjvOption()
        self._rect = mujoco.MjrRect(0, 0, width, height)

    def _update(self, data: mujoco.MjData, camera: int | mujoco.MjvCamera) -> None:
        if not isinstance(camera, mujoco.MjvCamera):
            fixed = mujoco.MjvCamera()
            fixed.type = mujoco.mjtCamera.mjCAMERA_FIXED
            fixed.fixedcamid = int(camera)
            camera = fixed
        mujoco.mjv_updateScene(self.model, data, self._option, None, camera,
                               mujoco.mjtCatBit.mjCAT_ALL.value, self._scene)

    def rgb(self, data: mujoco.MjData, camera: int | mujoco.MjvCamera) -> np.ndarray:
        """An RGB image (H x W x 3, uint8) from a camera id or a free MjvCamera."""
        gl_context()
        self._update(data, camera)
        image = np.empty((self.height, self.width, 3), dtype=np.uint8)
        mujoco.mjr_render(self._rect, self._scene, self._context)
        mujoco.mjr_readPixels(image, None, self._rect, self._context)
        return np.flipud(image).copy()

    def depth(self, data: mujoco.MjData, camera: int) -> np.ndarray:
        """Metric z-depth (H x W, metres), rendered as `mujoco.Renderer` does (segmentation colours)."""
        gl_context()
        self._update(data, camera)
        flags = self._scene.flags.copy()
        self._scene.flags[mujoco.mjtRndFlag.mjRND_SEGMENT] = True
        self._scene.flags[mujoco.mjtRndFlag.mjRND_IDCOLOR] = True
        try:
            raw = np.empty((self.height, self.width), dtype=np.float32)
            mujoco.mjr_render(self._rect, self._scene, self._context)
            mujoco.mjr_readPixels(None, raw, self._rect, self._context)
        finally:
            np.copyto(self._scene.flags, flags)
        return np.flipud(_metric_depth(raw, self.model)).copy()

    def close(self) -> None:
        """Free the model's render context (the GL context stays for the next model)."""
        if self._context is not None:
            gl_context()
            self._context.free()
            self._context = None


def _metric_depth(raw: np.ndarray, model: mujoco.MjModel) -> np.ndarray:
    """Depth-buffer values (0 near .. 1 far) to metres, in float32 as mujoco.Renderer computes them."""
    extent = model.stat.extent
    zfar = np.float32(model.vis.map.zfar * extent)
    znear = np.float32(model.vis.map.znear * extent)
    c_coef = np.float32(-0.5) * (-(zfar + znear) / (zfar - znear)) - np.float32(0.5)
    d_coef = np.float32(-0.5) * (-(np.float32(2) * zfar * znear) / (zfar - znear))
    return (d_coef / (raw.astype(np.float64) + c_coef)).astype(np.float32)
