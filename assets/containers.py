"""Open rectangular containers (tray, bin, box): a floor and four walls filling the box.

The floor covers the whole bottom face and the walls stand on it up to the rim, so
anything placed `completely on` the container rests on the rim plane and settles onto the
floor, and only the floor touches what the container stands on: a tray on a table makes 4
contacts, not 20 (walls reaching down to the table made four each, and were most of the
contacts MuJoCo solved in a Table-Cube episode). Thicknesses (the MuJoCo runner reads them here): a tray of the standard 0.2364 x
0.4522 x 0.028964 m box has a 5.8 mm floor and 9.5 mm walls.
"""

from __future__ import annotations

from prsc.assets.parts import Part, box


def _clamp(value: float, low: float, high: float) -> float:
    return max(low, min(high, value))


def open_box_parts(dimensions: tuple[float, float, float], floor: float, wall: float) -> tuple[Part, ...]:
    """Floor of thickness `floor` and four walls of thickness `wall`, open at the top."""
    w, l, h = dimensions
    floor = min(floor, 0.5 * h)
    wall = min(wall, 0.25 * min(w, l))
    # The long walls (x = +-) span the full length; the short ones fit between them.
    rise, z = h - floor, floor / 2  # the walls' height and centre above the floor
    return (
        box("floor", (w, l, floor), (0.0, 0.0, -h / 2 + floor / 2)),
        box("wall_left", (wall, l, rise), (-w / 2 + wall / 2, 0.0, z)),
        box("wall_right", (wall, l, rise), (w / 2 - wall / 2, 0.0, z)),
        box("wall_back", (w - 2 * wall, wall, rise), (0.0, -l / 2 + wall / 2, z)),
        box("wall_front", (w - 2 * wall, wall, rise), (0.0, l / 2 - wall / 2, z)),
    )


def tray_parts(dimensions: tuple[float, float, float]) -> tuple[Part, ...]:
    """A shallow tray: floor 20% of the height (5-15 mm), walls 4% of the short side (3-12 mm)."""
    w, l, h = dimensions
    return open_box_parts(dimensions, _clamp(0.2 * h, 0.005, 0.015), _clamp(0.04 * min(w, l), 0.003, 0.012))


def bin_parts(dimensions: tuple[float, float, float]) -> tuple[Part, ...]:
    """A storage bin: 10 mm floor, walls 3% of the short side (4-15 mm)."""
    w, l, h = dimensions
    return open_box_parts(dimensions, _clamp(0.05 * h, 0.005, 0.015), _clamp(0.03 * min(w, l), 0.004, 0.015))


def box_parts(dimensions: tuple[float, float, float]) -> tuple[Part, ...]:
    """A cardboard-like open box: thin floor and walls (2% of the short side, 3-10 mm)."""
    w, l, h = dimensions
    t = _clamp(0.02 * min(w, l), 0.003, 0.01)
    return open_box_parts(dimensions, t, t)
