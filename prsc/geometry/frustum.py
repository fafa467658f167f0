"""A pinhole camera's view frustum as half-space rows (docs/language.md, "`visible from C`").

The camera sits at its box centre and looks along its local +y, image up its local +z
(as every backend writes it). The frustum is the convex polytope between the near plane
(the front face of the camera's box, so nothing seen overlaps the camera) and the far
plane, bounded by the four planes through the optical centre and the image's edges.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

DEFAULT_FOVY = 60.0
"""Vertical field of view (degrees) of a camera that declares none, as the scene JSON's."""

DEFAULT_RESOLUTION = (640, 480)
"""(width, height) in pixels of a camera that declares none, as the scene JSON's."""

DEFAULT_FAR = 3.0
"""The far plane (m from the optical centre) of a camera that declares no `far`: a depth
camera's working range (RGB-D sensors of the Realsense class read reliably to about 3 m)."""


@dataclass(frozen=True)
class Frustum:
    """A view frustum in the camera's frame: near and far distances, half-angle tangents."""

    near: float
    far: float
    tan_x: float  # tan of the horizontal half-angle
    tan_z: float  # tan of the vertical half-angle

    def local_rows(self) -> tuple[np.ndarray, np.ndarray]:
        """(A, b) with A q <= b for points q in the camera frame (x right, y ahead, z up)."""
        a = np.array([
            [0.0, -1.0, 0.0],  # near: y >= near
            [0.0, 1.0, 0.0],  # far: y <= far
            [1.0, -self.tan_x, 0.0],  # right: x <= y tan_x
            [-1.0, -self.tan_x, 0.0],  # left
            [0.0, -self.tan_z, 1.0],  # top: z <= y tan_z
            [0.0, -self.tan_z, -1.0],  # bottom
        ])
        return a, np.array([-self.near, self.far, 0.0, 0.0, 0.0, 0.0])

    def world_rows(self, position: np.ndarray, rotation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(A, b) in the world for a camera at `position` with local axes the columns of `rotation`."""
        a_local, b_local = self.local_rows()
        a = a_local @ rotation.T  # a . R^T (p - c) <= b  <=>  (a R^T) . p <= b + (a R^T) . c
        return a, b_local + a @ position


def frustum(near: float, far: float, fovy_deg: float, resolution: tuple[float, float]) -> Frustum:
    """The frustum of a camera with vertical field of view `fovy_deg` and `resolution` (w, h)."""
    tan_z = math.tan(math.radians(fovy_deg) / 2)
    return Frustum(float(near), float(far), tan_z * resolution[0] / resolution[1], tan_z)
