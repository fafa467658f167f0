"""An open container's interior: the floor's top and the walls' inner faces, in its box frame.

The one description of a container that the sampler (where things rest on it) and every
backend (the floor and wall solids they build) read. A class declares it with the
properties `floorThickness`, `wallThickness` and `container` ("box" or "round");
docs/language.md, "Containers". A container asset whose class declares none is built with
the asset's own interior (ASSET_INTERIORS), which the sampler does not know: there the
object rests on the rim, and `prsc compile --settle-check` says so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, Mapping

import numpy as np

ROUND_SIDES = 16
"""Wall slabs of a round container; the interior is the regular polygon of their inner faces."""

SHAPES = ("box", "round")


@dataclass(frozen=True)
class Interior:
    """A container's walls and floor fitted to its box (thicknesses clamped to fit)."""

    dimensions: tuple[float, float, float]
    floor: float  # floor thickness: the floor's top is `floor` above the box bottom
    wall: float  # wall thickness, inward from the box side (round: from the inscribed circle)
    shape: str  # "box" | "round"

    @property
    def floor_top(self) -> float:
        """Height of the floor's top above the box centre (negative: below it)."""
        return -self.dimensions[2] / 2 + self.floor

    @property
    def radius(self) -> float:
        """The round container's outer radius (the circle inscribed in the box's footprint)."""
        return min(self.dimensions[0], self.dimensions[1]) / 2

    def edges(self) -> tuple[np.ndarray, np.ndarray]:
        """The interior's footprint as rows m . q <= c on (x, y) in the box frame: (m (k, 2), c (k,))."""
        if self.shape == "round":
            angles = 2 * np.pi * np.arange(ROUND_SIDES) / ROUND_SIDES
            normals = np.stack([np.cos(angles), np.sin(angles)], axis=1)
            return normals, np.full(ROUND_SIDES, self.radius - self.wall)
        w, l, _ = self.dimensions
        normals = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]])
        return normals, np.array([w / 2 - self.wall] * 2 + [l / 2 - self.wall] * 2)

    def slab_chord(self) -> float:
        """A round wall slab's width: neighbouring slabs meet on the interior polygon."""
        return 2 * (self.radius - self.wall) * math.tan(math.pi / ROUND_SIDES)


def fit_interior(dimensions: tuple[float, float, float], floor: float, wall: float, shape: str) -> Interior:
    """The interior of a container of this box: floor at most half the height, walls at most
    a quarter of the short side (box) or 0.3 of the radius (round), so an interior remains."""
    w, l, h = (float(v) for v in dimensions)
    if shape not in SHAPES:
        raise ValueError(f"container must be one of {', '.join(SHAPES)}, not {shape!r}")
    limit = 0.3 * min(w, l) / 2 if shape == "round" else 0.25 * min(w, l)
    return Interior((w, l, h), min(max(float(floor), 0.0), 0.5 * h), min(max(float(wall), 0.0), limit), shape)


PROPERTIES = ("floorThickness", "wallThickness", "container")
"""The properties by which a class declares an interior (all three, or none)."""


def declared_interior(dimensions: tuple[float, float, float], properties: Mapping[str, Any]) -> Interior | None:
    """The interior an object's properties declare, or None when it declares none."""
    if not any(p in properties for p in PROPERTIES):
        return None
    missing = [p for p in PROPERTIES if p not in properties]
    if missing:
        raise ValueError(f"a container declares {', '.join(PROPERTIES)} together; missing {', '.join(missing)}")
    floor, wall, shape = (properties[p] for p in PROPERTIES)
    for name, value in (("floorThickness", floor), ("wallThickness", wall)):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not value >= 0:
            raise ValueError(f"{name} must be a number >= 0, not {value!r}")
    return fit_interior(dimensions, floor, wall, str(shape))


def _clamp(value: float, low: float, high: float) -> float:
    return max(low, min(high, value))


def _box_asset(floor_fraction: float, floor_range: tuple[float, float], wall_fraction: float,
               wall_range: tuple[float, float]) -> Callable[[tuple[float, float, float]], Interior]:
    """A box container asset's interior: floor a fraction of the height, walls of the short side, clamped."""
    def interior(dimensions: tuple[float, float, float]) -> Interior:
        w, l, h = dimensions
        return fit_interior(dimensions, _clamp(floor_fraction * h, *floor_range),
                            _clamp(wall_fraction * min(w, l), *wall_range), "box")
    return interior


def _round_asset(wall_fraction: float, floor_fraction: float) -> Callable[[tuple[float, float, float]], Interior]:
    """A round vessel asset's interior: walls and floor as fractions of the radius and height (>= 2 mm)."""
    def interior(dimensions: tuple[float, float, float]) -> Interior:
        radius, h = min(dimensions[0], dimensions[1]) / 2, dimensions[2]
        return fit_interior(dimensions, max(floor_fraction * h, 0.002), max(wall_fraction * radius, 0.002), "round")
    return interior


ASSET_INTERIORS: dict[str, Callable[[tuple[float, float, float]], Interior]] = {
    "tray": _box_asset(0.2, (0.005, 0.015), 0.04, (0.003, 0.012)),  # shallow: a thick floor
    "bin": _box_asset(0.05, (0.005, 0.015), 0.03, (0.004, 0.015)),
    "box": lambda d: fit_interior(d, *(_clamp(0.02 * min(d[0], d[1]), 0.003, 0.01),) * 2, "box"),  # cardboard-like
    "bowl": _round_asset(wall_fraction=0.06, floor_fraction=0.15),  # wide, low walls, thick base
    "cup": _round_asset(wall_fraction=0.08, floor_fraction=0.08),
    "bucket": _round_asset(wall_fraction=0.04, floor_fraction=0.05),
    "plate": _round_asset(wall_fraction=0.05, floor_fraction=0.4),  # a thick disc, a low rim
}
"""The interior each container asset is built with when its class declares none, by model name."""


def asset_interior(model: str | None, dimensions: tuple[float, float, float]) -> Interior | None:
    """The interior of container asset `model` fitted to the box, or None for other models."""
    recipe = ASSET_INTERIORS.get(model or "")
    return None if recipe is None else recipe(tuple(float(v) for v in dimensions))  # type: ignore[arg-type]

