"""A rigid part of an asset: one primitive (or mesh) placed in the object's box frame."""

from __future__ import annotations

import math
from dataclasses import dataclass

IDENTITY = (1.0, 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Part:
    """One solid of an asset, in the object frame (origin at the box centre, metres).

    `size` is the part's full extent along its own x, y, z: a box's edge lengths, a
    cylinder's (2r, 2r, height) with its axis along z, a sphere's (2r, 2r, 2r), a mesh's
    bounding box (the mesh file is normalised to a unit cube centred at its origin).
    """

    name: str
    shape: str  # box | cylinder | sphere | mesh
    size: tuple[float, float, float]
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    quaternion: tuple[float, float, float, float] = IDENTITY  # w x y z
    collides: bool = True
    mesh: str | None = None  # normalised mesh file (absolute path) for shape "mesh"
    visible: bool = True  # False: collision geometry only (a convex piece of a decomposed mesh)
    texture: str | None = None  # base-colour image (absolute path) of a textured mesh part, read through its UVs
    maps: tuple[tuple[str, str], ...] = ()  # (role, absolute path) of its normal and ORM maps, beside `texture`

    @property
    def radius(self) -> float:
        """Radius of a cylinder or sphere part."""
        return min(self.size[0], self.size[1]) / 2 if self.shape == "cylinder" else min(self.size) / 2

    @property
    def volume(self) -> float:
        """Solid volume of the primitive (a mesh counts as its box until measured)."""
        if self.shape == "cylinder":
            return math.pi * self.radius**2 * self.size[2]
        if self.shape == "sphere":
            return 4.0 / 3.0 * math.pi * self.radius**3
        return self.size[0] * self.size[1] * self.size[2]


def box(name: str, size: tuple[float, float, float], position=(0.0, 0.0, 0.0), quaternion=IDENTITY, collides=True) -> Part:
    """A box part of full edge lengths `size`."""
    return Part(name, "box", tuple(float(v) for v in size), tuple(float(v) for v in position), tuple(quaternion), collides)


def cylinder(name: str, radius: float, height: float, position=(0.0, 0.0, 0.0), collides=True) -> Part:
    """A z-axis cylinder part."""
    return Part(name, "cylinder", (2 * radius, 2 * radius, float(height)), tuple(float(v) for v in position), IDENTITY, collides)


def sphere(name: str, radius: float, position=(0.0, 0.0, 0.0), collides=True) -> Part:
    """A sphere part."""
    d = 2 * float(radius)
    return Part(name, "sphere", (d, d, d), tuple(float(v) for v in position), IDENTITY, collides)
