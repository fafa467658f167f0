"""The visible housing of a camera: a box filling the back half of the object's box.

The lens sits at the box centre looking along +y, so the housing stays behind the image
plane and never appears in the camera's own view. It never collides (a camera is a sensor).
"""

from __future__ import annotations

from prsc.assets.parts import Part, box


def camera_parts(dimensions: tuple[float, float, float]) -> tuple[Part, ...]:
    """Non-colliding housing behind the camera's optical centre."""
    w, l, h = dimensions
    depth = 0.45 * l  # leaves a gap of 5% of the length in front of the housing
    return (box("housing", (w, depth, h), (0.0, -l / 2 + depth / 2, 0.0), collides=False),)
