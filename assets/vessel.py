"""Round open vessels (bowl, cup, bucket, plate): a disc floor and a ring of wall slabs.

Walls are separate convex slabs so every simulator sees a hollow (concave) container that
objects can sit inside, rather than the solid convex hull a single mesh collider gives.
"""

from __future__ import annotations

import math

from prsc.assets.parts import Part, box, cylinder

SEGMENTS = 16


def vessel_parts(
    dimensions: tuple[float, float, float],
    wall_fraction: float,
    floor_fraction: float,
    segments: int = SEGMENTS,
) -> tuple[Part, ...]:
    """A cylindrical vessel inscribed in the box: floor disc plus `segments` wall slabs."""
    w, l, h = dimensions
    radius = min(w, l) / 2
    wall = min(max(wall_fraction * radius, 0.002), 0.3 * radius)
    floor = min(max(floor_fraction * h, 0.002), 0.5 * h)
    parts = [cylinder("floor", radius - wall, floor, (0.0, 0.0, -h / 2 + floor / 2))]
    apothem = radius - wall / 2
    # Inner edges of neighbouring slabs meet on the inner polygon; outer faces stay inside
    # the inscribed circle's square, so the vessel never leaves the object's box.
    chord = 2 * (radius - wall) * math.tan(math.pi / segments)
    for k in range(segments):
        theta = 2 * math.pi * k / segments
        # The slab's local y points outward (radially); yaw it to angle theta - 90 deg.
        yaw = theta - math.pi / 2
        quat = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
        parts.append(
            box(f"wall_{k:02d}", (chord, wall, h), (apothem * math.cos(theta), apothem * math.sin(theta), 0.0), quat)
        )
    return tuple(parts)


def bowl_parts(dimensions: tuple[float, float, float]) -> tuple[Part, ...]:
    """A bowl: wide, low walls and a thick base."""
    return vessel_parts(dimensions, wall_fraction=0.06, floor_fraction=0.15)


def cup_parts(dimensions: tuple[float, float, float]) -> tuple[Part, ...]:
    """A cup: tall walls and a thin base."""
    return vessel_parts(dimensions, wall_fraction=0.08, floor_fraction=0.08)


def bucket_parts(dimensions: tuple[float, float, float]) -> tuple[Part, ...]:
    """A bucket: tall thin walls."""
    return vessel_parts(dimensions, wall_fraction=0.04, floor_fraction=0.05)


def plate_parts(dimensions: tuple[float, float, float]) -> tuple[Part, ...]:
    """A plate: a thick disc with a low rim."""
    return vessel_parts(dimensions, wall_fraction=0.05, floor_fraction=0.4)
