"""Round open vessels (bowl, cup, bucket, plate): a disc floor and a ring of wall slabs.

Walls are separate convex slabs so every simulator sees a hollow (concave) container that
objects can sit inside, rather than the solid convex hull a single mesh collider gives.
The slabs' inner faces are the interior polygon the sampler places things in
(prsc.geometry.container).
"""

from __future__ import annotations

import math

from prsc.assets.parts import Part, box, cylinder
from prsc.geometry.container import ROUND_SIDES, Interior


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
