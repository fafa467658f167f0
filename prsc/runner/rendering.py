"""Offscreen rendering of a model with the process's shared GL context (see gl.py).

A MuJoCo render context (MjrContext) holds what the GPU side needs of a model: its
meshes, textures, height fields, skins and materials' textures, plane grids, buffer
sizes. Uploading an arm's meshes costs about 0.1 CPU s, so a worker keeps the context
of the last model and hands it to the next model with the same render assets and the same
`context_inputs` (the numbers a context bakes in), after setting the numbers it derives from
stat.extent, which differs from scene to scene (`context_patch`: the shadow clip and the fog
range). The images are the same bits a fresh context renders (tests/runner/test_rendering.py,
tests/api/test_renderer_reuse.py); `prsc.SceneEnv`'s renderers follow the same rule.
"""

from __future__ import annotations

import hashlib
import os

import mujoco
import numpy as np

from prsc.runner.faults import InfrastructureError
from prsc.runner.gl import gl_context


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
        self._context = _render_context(model)
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
        return self._render_rgb()

    def depth(self, data: mujoco.MjData, camera: int) -> np.ndarray:
        """Metric z-depth (H x W, metres), rendered as `mujoco.Renderer` does (segmentation colours)."""
        gl_context()
        self._update(data, camera)
        return self._render_depth()

    def rgb_depth(self, data: mujoco.MjData, camera: int) -> tuple[np.ndarray, np.ndarray]:
        """`rgb` and `depth` of one camera from one update of the scene."""
        gl_context()
        self._update(data, camera)
        return self._render_rgb(), self._render_depth()

    def _render_rgb(self) -> np.ndarray:
        image = np.empty((self.height, self.width, 3), dtype=np.uint8)
        mujoco.mjr_render(self._rect, self._scene, self._context)
        mujoco.mjr_readPixels(image, None, self._rect, self._context)
        return np.flipud(image).copy()

    def _render_depth(self) -> np.ndarray:
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
        """Done with this model (its render context stays for the next model with the same assets)."""
        self._context = None


_kept: tuple[tuple[str, tuple], mujoco.MjrContext] | None = None  # ((assets digest, context inputs), context) of the last model


def _render_key(model: mujoco.MjModel) -> str:
    """A digest of everything mjr_makeContext uploads or sizes from a model, except the per-scene numbers."""
    digest = hashlib.sha256()
    planes = model.geom_type == mujoco.mjtGeom.mjGEOM_PLANE
    parts = [model.geom_size[planes], model.geom_matid[planes], np.array([model.ngeom])]
    for prefix in ("mesh_", "tex_", "hfield_", "skin_", "mat_", "flex_"):
        parts += [getattr(model, n) for n in sorted(dir(model)) if n.startswith(prefix)
                  and isinstance(getattr(model, n, None), np.ndarray)]
    g, q = model.vis.global_, model.vis.quality
    parts.append(np.array([g.offwidth, g.offheight, q.offsamples, q.shadowsize, q.numslices, q.numstacks,
                           q.numquads, model.nmesh, model.ntex, model.nhfield, model.nskin, model.nmat]))
    for part in parts:
        array = np.ascontiguousarray(part)
        digest.update(str(array.dtype).encode() + str(array.shape).encode())
        digest.update(array.tobytes())
    return digest.hexdigest()


PLANE = int(mujoco.mjtGeom.mjGEOM_PLANE)  # an int: numpy compares an array with MuJoCo's enum 6x slower


def context_inputs(model: mujoco.MjModel) -> tuple:
    """The numbers of a model that a render context bakes in when made, besides its assets, and
    that `scenario.apply` or a user may change: a context made with others must be made again.
    MuJoCo's mjr_makeContext (src/render/classic/render_context.c) builds each plane's grid from
    its size, or, along an infinite side, over 2.1 * zfar * stat.extent: then the extent is one
    of them (a context made at another extent draws such a plane from other vertices, a pixel
    or two one level off, docs/learning.md). prsc's ground is finite, so the extent is not; the
    numbers it sets are `context_patch`'s. Cheap: compared at every render."""
    planes = model.geom_type == PLANE
    m, g = model.vis.map, model.vis.global_
    infinite = bool(np.any(model.geom_size[planes, :2] == 0))
    return (float(model.stat.extent) if infinite else None, m.zfar, m.shadowscale, tuple(model.vis.rgba.fog),
            g.linewidth, model.geom_size[planes].tobytes(), model.geom_matid[planes].tobytes(),
            model.mat_texid.tobytes(), model.mat_texuniform.tobytes(), model.mat_texrepeat.tobytes())


def context_patch(model: mujoco.MjModel) -> tuple[float, float, float]:
    """The numbers a render context derives from stat.extent that a kept context takes in place:
    (shadowClip, fogStart, fogEnd), as mjr_makeContext computes them (float32 of a double)."""
    extent, m = float(model.stat.extent), model.vis.map
    return tuple(float(np.float32(extent * float(v))) for v in (m.shadowclip, m.fogstart, m.fogend))


def patch_context(context: mujoco.MjrContext, patch: tuple[float, float, float]) -> None:
    """Give a kept render context the `context_patch` numbers of the model it renders now; its
    GL context must be current. mjr_render reads shadowClip from the context but the fog range
    from GL state, which mjr_makeContext sets (glFog), so both are set here."""
    from OpenGL import GL  # MuJoCo's own GL backends use PyOpenGL, on the platform MuJoCo chose

    context.shadowClip, context.fogStart, context.fogEnd = patch
    GL.glFogf(GL.GL_FOG_START, context.fogStart)
    GL.glFogf(GL.GL_FOG_END, context.fogEnd)


_counts = {"contexts made": 0, "contexts patched": 0}  # this process's counts, for benchmarks


def context_counts() -> dict[str, int]:
    """How many render contexts this process made and patched in place (`_render_context`)."""
    return dict(_counts)


def _render_context(model: mujoco.MjModel) -> mujoco.MjrContext:
    """This worker's render context for a model: the kept one when the render assets and
    `context_inputs` match (patched to the model's `context_patch`), else a new one."""
    global _kept
    key = (_render_key(model), context_inputs(model))
    if _kept is not None and _kept[0] == key:
        context = _kept[1]
        patch = context_patch(model)
        if patch != (context.shadowClip, context.fogStart, context.fogEnd):
            patch_context(context, patch)
            _counts["contexts patched"] += 1
    else:
        if _kept is not None:
            _kept[1].free()
            _kept = None
        try:
            context = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150.value)
        except mujoco.FatalError as error:
            raise InfrastructureError(f"no offscreen OpenGL rendering with MUJOCO_GL={os.environ.get('MUJOCO_GL', '')!r} "
                                      f"(MuJoCo: {str(error).strip()}); unset MUJOCO_GL to let prsc choose "
                                      "EGL or OSMesa") from None
        _counts["contexts made"] += 1
        _kept = (key, context)
    mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, context)
    context.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
    return context


def _metric_depth(raw: np.ndarray, model: mujoco.MjModel) -> np.ndarray:
    """Depth-buffer values (0 near .. 1 far) to metres, in float32 as mujoco.Renderer computes them."""
    extent = model.stat.extent
    zfar = np.float32(model.vis.map.zfar * extent)
    znear = np.float32(model.vis.map.znear * extent)
    c_coef = np.float32(-0.5) * (-(zfar + znear) / (zfar - znear)) - np.float32(0.5)
    d_coef = np.float32(-0.5) * (-(np.float32(2) * zfar * znear) / (zfar - znear))
    return (d_coef / (raw.astype(np.float64) + c_coef)).astype(np.float32)
