"""Cube localisation from the ceiling RGB-D camera: colour segmentation + depth back-projection."""

from __future__ import annotations

import colorsys
import math
from dataclasses import dataclass

import mujoco
import numpy as np
from scipy import ndimage

from prsc.runner.rendering import OffscreenRenderer

# Perception images are rendered smaller than the camera's nominal resolution (same aspect
# and field of view, so the same intrinsics up to scale): it keeps rendering cheap.
PERCEPTION_WIDTH = 320
PERCEPTION_HEIGHT = 240
MIN_BLOB_PIXELS = 6
# Pixels within this depth of the blob's nearest pixel belong to the face facing the camera.
TOP_FACE_DEPTH_BAND = 0.006


@dataclass(frozen=True)
class Intrinsics:
    """Pinhole intrinsics of a rendered image (pixels); v grows downwards."""

    width: int
    height: int
    focal: float
    cx: float
    cy: float


@dataclass(frozen=True)
class Detection:
    """A cube found in an image: its estimated world centre and the pixels it covered."""

    centre: np.ndarray
    pixels: int
    touches_border: bool


def intrinsics_for(model: mujoco.MjModel, camera_id: int, width: int, height: int) -> Intrinsics:
    """Intrinsics of a MuJoCo camera (vertical `fovy`, square pixels) at a render size."""
    fovy = math.radians(float(model.cam_fovy[camera_id]))
    focal = (height / 2) / math.tan(fovy / 2)
    return Intrinsics(width, height, focal, width / 2, height / 2)


def colour_mask(rgb: np.ndarray, target_rgba) -> np.ndarray:
    """Pixels whose colour matches a target colour: by hue when it is saturated, else by value."""
    r, g, b = (float(c) for c in target_rgba[:3])
    hue, sat, val = colorsys.rgb_to_hsv(r, g, b)
    image = rgb.astype(np.float32) / 255.0
    mx = image.max(axis=2)
    mn = image.min(axis=2)
    chroma = mx - mn
    pixel_sat = np.where(mx > 0, chroma / np.maximum(mx, 1e-6), 0.0)
    if sat > 0.3:
        # Lighting scales brightness and washes out saturation, but keeps hue: segment on it.
        rr, gg, bb = image[..., 0], image[..., 1], image[..., 2]
        safe = np.maximum(chroma, 1e-6)
        h = np.where(mx == rr, ((gg - bb) / safe) % 6, np.where(mx == gg, (bb - rr) / safe + 2, (rr - gg) / safe + 4)) / 6
        dist = np.abs(h - hue)
        dist = np.minimum(dist, 1 - dist)
        return (pixel_sat > 0.45) & (dist < 0.06) & (mx > 0.08)
    # Grey-ish targets: match brightness among unsaturated pixels.
    return (pixel_sat < 0.15) & (np.abs(mx - val) < 0.08)


def deproject(us: np.ndarray, vs: np.ndarray, depth: np.ndarray, intr: Intrinsics,
              cam_pos: np.ndarray, cam_mat: np.ndarray) -> np.ndarray:
    """World points (N x 3) of pixel centres (u, v) at z-depths, for a MuJoCo camera pose."""
    x = (us + 0.5 - intr.cx) / intr.focal * depth
    y = -(vs + 0.5 - intr.cy) / intr.focal * depth
    local = np.stack([x, y, -depth], axis=1)  # a MuJoCo camera looks along its -z, +y up
    return cam_pos + local @ cam_mat.T


def locate_cube(rgb: np.ndarray, depth: np.ndarray, intr: Intrinsics, cam_pos: np.ndarray,
                cam_mat: np.ndarray, colour, half_height: float) -> Detection | None:
    """Find the largest blob of the cube's colour and estimate the cube's centre in the world.

    The centroid of the camera-facing face (pixels within a few mm of the blob's nearest
    depth) is back-projected, then moved down by half the cube's height. Occlusion or a
    cube cut by the image border bias this estimate, as they would on a real robot.
    """
    mask = colour_mask(rgb, colour)
    labels, count = ndimage.label(mask)
    if count == 0:
        return None
    sizes = ndimage.sum_labels(mask, labels, index=np.arange(1, count + 1))
    best = int(np.argmax(sizes)) + 1
    if sizes[best - 1] < MIN_BLOB_PIXELS:
        return None
    blob = labels == best
    vs, us = np.nonzero(blob)
    # Depth is read inside the blob only: its rim pixels mix in whatever lies behind or in
    # front (flying pixels), which would drag the estimate off the cube.
    inner = ndimage.binary_erosion(blob)
    ivs, ius = np.nonzero(inner) if inner.any() else (vs, us)
    d = depth[ivs, ius]
    top = d <= d.min() + TOP_FACE_DEPTH_BAND
    points = deproject(ius[top].astype(float), ivs[top].astype(float), d[top], intr, cam_pos, cam_mat)
    centre = points.mean(axis=0) - np.array([0.0, 0.0, half_height])
    border = bool(us.min() == 0 or vs.min() == 0 or us.max() == intr.width - 1 or vs.max() == intr.height - 1)
    return Detection(centre=centre, pixels=int(len(us)), touches_border=border)


class CeilingCamera:
    """Renders RGB and depth from one named MuJoCo camera at the perception resolution."""

    def __init__(self, model: mujoco.MjModel, camera_name: str,
                 width: int = PERCEPTION_WIDTH, height: int = PERCEPTION_HEIGHT):
        self.model = model
        self.camera_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera_name)
        if self.camera_id < 0:
            raise KeyError(f"camera {camera_name!r} not in the MJCF")
        self.intrinsics = intrinsics_for(model, self.camera_id, width, height)
        self._renderer = OffscreenRenderer(model, width, height)

    def capture(self, data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """An RGB image (H x W x 3, uint8) and a metric z-depth image (H x W, metres)."""
        return self._renderer.rgb_depth(data, self.camera_id)

    def pose(self, data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """World position and rotation matrix (columns = camera axes) of the camera."""
        return data.cam_xpos[self.camera_id].copy(), data.cam_xmat[self.camera_id].reshape(3, 3).copy()

    def close(self) -> None:
        """Release the model's render context."""
        self._renderer.close()
