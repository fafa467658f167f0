"""Oriented boxes: centre, rotation (columns = local axes in world) and half extents.

The support function of a box centred at the origin is s(n) = sum_i h_i |n . R e_i|: the
half-thickness of the box along n (for unit n), and the quantity every erosion, `on` and
collision test in prsc is built from.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

# The 8 corner sign patterns, in binary order (x fastest).
CORNER_SIGNS: NDArray[np.float64] = np.array(
    [[sx, sy, sz] for sz in (-1.0, 1.0) for sy in (-1.0, 1.0) for sx in (-1.0, 1.0)]
)


def support(rotation: ArrayLike, half_extents: ArrayLike, normals: ArrayLike) -> NDArray[np.float64]:
    """Support s(n) = sum_i h_i |n . R e_i| of an origin-centred box, for n of shape (..., 3)."""
    n = np.asarray(normals, dtype=float)
    return np.abs(n @ np.asarray(rotation, dtype=float)) @ np.asarray(half_extents, dtype=float)


@dataclass(frozen=True, eq=False)
class Box:
    """An oriented box: `center` (3,), `rotation` (3, 3), `half_extents` (3,) >= 0."""

    center: NDArray[np.float64]
    rotation: NDArray[np.float64]
    half_extents: NDArray[np.float64]

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", np.asarray(self.center, dtype=float).reshape(3))
        object.__setattr__(self, "rotation", np.asarray(self.rotation, dtype=float).reshape(3, 3))
        h = np.asarray(self.half_extents, dtype=float).reshape(3)
        if np.any(h < 0) or not np.all(np.isfinite(h)):
            raise ValueError(f"box half extents must be finite and >= 0, got {h.tolist()}")
        object.__setattr__(self, "half_extents", h)

    @classmethod
    def from_dimensions(cls, center: ArrayLike, rotation: ArrayLike, dimensions: ArrayLike) -> Box:
        """A box from its full (width, length, height) instead of half extents."""
        return cls(center, rotation, np.asarray(dimensions, dtype=float) / 2.0)

    @property
    def dimensions(self) -> NDArray[np.float64]:
        """Full (width, length, height)."""
        return 2.0 * self.half_extents

    @property
    def volume(self) -> float:
        """Volume of the box."""
        return float(np.prod(2.0 * self.half_extents))

    def support(self, normals: ArrayLike) -> NDArray[np.float64]:
        """Half-thickness s(n) of the box along each n (..., 3) (about its centre)."""
        return support(self.rotation, self.half_extents, normals)

    def extent_along(self, normals: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(min, max) of n . x over the box for each n (..., 3)."""
        n = np.asarray(normals, dtype=float)
        mid = n @ self.center
        s = self.support(n)
        return mid - s, mid + s

    def corners(self) -> NDArray[np.float64]:
        """The 8 corners (8, 3), x sign fastest."""
        return self.center + (CORNER_SIGNS * self.half_extents) @ self.rotation.T

    def face_point(self, signs: ArrayLike) -> NDArray[np.float64]:
        """Point center + R (signs * h) for signs in {-1, 0, 1}^3 (e.g. top = (0, 0, 1))."""
        return self.center + self.rotation @ (np.asarray(signs, dtype=float) * self.half_extents)

    def aabb(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Axis-aligned bounding box (lo, hi)."""
        r = np.abs(self.rotation) @ self.half_extents
        return self.center - r, self.center + r

    def contains(self, points: ArrayLike, tol: float = 1e-9) -> NDArray[np.bool_]:
        """Whether each point (..., 3) lies in the box (within tol along each local axis)."""
        local = (np.asarray(points, dtype=float) - self.center) @ self.rotation
        return np.all(np.abs(local) <= self.half_extents + tol, axis=-1)
