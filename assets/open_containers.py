"""Open containers built from their interior (prsc.geometry.container): a floor and walls.

A box container's floor covers the whole bottom face and its walls stand on it up to the
rim, so only the floor touches what the container stands on: a tray on a table makes 4
contacts, not 20 (walls reaching down to the table made four each, and were most of the
contacts MuJoCo solved in a Table-Cube episode). A round container (prsc.assets.vessel)
has a disc floor and a ring of wall slabs. The thicknesses come from the object's
declared interior (the model library declares them per class, docs/language.md), else
from the asset's own (prsc.geometry.container.ASSET_INTERIORS), which the sampler reads too.
"""

from __future__ import annotations

import functools

from prsc.assets.parts import Part, box
from prsc.assets.vessel import vessel_parts
from prsc.geometry.container import Interior


def open_box_parts(interior: Interior) -> tuple[Part, ...]:
    """The floor and four walls of a box container, open at the top."""
    w, l, h = interior.dimensions
    floor, wall = interior.floor, interior.wall
    # The long walls (x = +-) span the full length; the short ones fit between them.
    rise, z = h - floor, floor / 2  # the walls' height and centre above the floor
    return (
        box("floor", (w, l, floor), (0.0, 0.0, -h / 2 + floor / 2)),
        box("wall_left", (wall, l, rise), (-w / 2 + wall / 2, 0.0, z)),
        box("wall_right", (wall, l, rise), (w / 2 - wall / 2, 0.0, z)),
        box("wall_back", (w - 2 * wall, wall, rise), (0.0, -l / 2 + wall / 2, z)),
        box("wall_front", (w - 2 * wall, wall, rise), (0.0, l / 2 - wall / 2, z)),
    )


@functools.lru_cache(maxsize=256)  # a pure function of the frozen interior: built once per box
def container_parts(interior: Interior) -> tuple[Part, ...]:
    """The solids of a container with this interior (box or round)."""
    return vessel_parts(interior) if interior.shape == "round" else open_box_parts(interior)
