"""Round open vessels (bowl, cup, bucket, plate): a disc floor and a ring of wall slabs.

Walls are separate convex slabs so every simulator sees a hollow (concave) container that
objects can sit inside, rather than the solid convex hull a single mesh collider gives.
The slabs' inner faces are the interior polygon the sampler places things in
(prsc.geometry.container).
"""

from __future__ import annotations

import math

from prsc.assets.parts import Part, box, cylinder
from prsc.geometry.container import ROUND_SIDES, Interior, fit_interior


def vessel_parts(interior: Interior) -> tuple[Part, ...]:
    """A cylindrical vessel inscribed in the box: floor disc plus ROUND_SIDES wall slabs."""
    _, _, h = interior.dimensions
    radius, wall, floor = interior.radius, interior.wall, interior.floor
    parts = [cylinder("floor", radius - wall, floor, (0.0, 0.0, -h / 2 + floor / 2))]
    apothem = radius - wall / 2
    # Inner edges of neighbouring slabs meet on the inner polygon; outer faces stay inside
    # the inscribed circle's square, so the vessel never leaves the object's box.
    chord = interior.slab_chord()
    for k in range(ROUND_SIDES):
        theta = 2 * math.pi * k / ROUND_SIDES
        # The slab's local y points outward (radially); yaw it to angle theta - 90 deg.
        yaw = theta - math.pi / 2
        quat = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
        parts.append(
            box(f"wall_{k:02d}", (chord, wall, h), (apothem * math.cos(theta), apothem * math.sin(theta), 0.0), quat)
        )
    return tuple(parts)


def _fractions(dimensions: tuple[float, float, float], wall_fraction: float, floor_fraction: float) -> Interior:
    """A round interior with walls and floor as fractions of the radius and height (>= 2 mm)."""
    radius, h = min(dimensions[0], dimensions[1]) / 2, dimensions[2]
    return fit_interior(dimensions, max(floor_fraction * h, 0.002), max(wall_fraction * radius, 0.002), "round")


def bowl_parts(dimensions: tuple[float, float, float]) -> tuple[Part, ...]:
    """A bowl: wide, low walls and a thick base."""
    return vessel_parts(_fractions(dimensions, wall_fraction=0.06, floor_fraction=0.15))


def cup_parts(dimensions: tuple[float, float, float]) -> tuple[Part, ...]:
    """A cup: tall walls and a thin base."""
    return vessel_parts(_fractions(dimensions, wall_fraction=0.08, floor_fraction=0.08))


def bucket_parts(dimensions: tuple[float, float, float]) -> tuple[Part, ...]:
    """A bucket: tall thin walls."""
    return vessel_parts(_fractions(dimensions, wall_fraction=0.04, floor_fraction=0.05))


def plate_parts(dimensions: tuple[float, float, float]) -> tuple[Part, ...]:
    """A plate: a thick disc with a low rim."""
    return vessel_parts(_fractions(dimensions, wall_fraction=0.05, floor_fraction=0.4))
