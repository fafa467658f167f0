"""The support function of an object's box: what erosion (`completely`) subtracts per row."""

from __future__ import annotations

import numpy as np

from prsc.geometry.boxes import support as box_support


class Support:
    """The support function s(n) of the object's box about its centre (docs/sampling.md).

    mode "exact": rotation known; "yaw": rotation is an unknown yaw (facing toward), so
    use the footprint's radius horizontally (exact vertically); "free": rotation unknown,
    use the box's circumradius.
    """

    __slots__ = ("rotation", "half", "mode", "_radius_xy", "_radius")

    def __init__(self, rotation: np.ndarray | None, half_extents: np.ndarray, mode: str = "exact") -> None:
        self.rotation = rotation
        self.half = np.asarray(half_extents, dtype=float)
        self.mode = mode
        self._radius_xy = float(np.hypot(self.half[0], self.half[1]))
        self._radius = float(np.linalg.norm(self.half))

    def __call__(self, normals: np.ndarray) -> np.ndarray:
        """s(n) for each row of normals (m, 3); positively homogeneous in n."""
        n = np.asarray(normals, dtype=float)
        if self.mode == "exact":
            return box_support(self.rotation, self.half, n)
        if self.mode == "yaw":
            return np.abs(n[..., 2]) * self.half[2] + np.hypot(n[..., 0], n[..., 1]) * self._radius_xy
        return np.linalg.norm(n, axis=-1) * self._radius
