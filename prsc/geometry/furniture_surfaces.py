"""Furniture's support surfaces: the shelf's boards and the table's top, in the box frame.

The one description the sampler (where `on shelf.boards[k]` rests an object) and the asset
recipes (assets/furniture.py builds the boards from `shelf_layout`) both read, so a spec's
surfaces and the built geometry cannot disagree; docs/language.md, "Support surfaces".
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

SHELF_BOARDS = 4
"""Boards of a shelf asset, bottom (0) to top (3)."""


@dataclass(frozen=True)
class Surface:
    """A horizontal support rectangle in its object's box frame, and the free height above it."""

    centre: tuple[float, float, float]  # the rectangle's centre (on the surface's top)
    width: float  # along the box's x
    length: float  # along the box's y
    clearance: float | None  # height to the next part above (None: open above)


@dataclass(frozen=True)
class ShelfLayout:
    """A shelf fitted to its box: panel thickness and the boards' centre heights."""

    dimensions: tuple[float, float, float]
    thickness: float
    board_z: tuple[float, ...]  # each board's centre height in the box frame

    def board(self, k: int) -> Surface:
        """Board k's top: between the side panels, from the back panel to the open front."""
        w, l, _ = self.dimensions
        t = self.thickness
        top = self.board_z[k] + t / 2
        above = self.board_z[k + 1] - t / 2 - top if k + 1 < len(self.board_z) else None
        return Surface((0.0, t / 2, top), w - 2 * t, l - t, above)


def shelf_layout(dimensions: tuple[float, float, float], boards: int = SHELF_BOARDS) -> ShelfLayout:
    """The panel thickness (2.5% of the short side, 12..30 mm) and `boards` evenly spaced boards."""
    w, l, h = (float(v) for v in dimensions)
    t = min(max(0.025 * min(w, l), 0.012), 0.03, 0.2 * min(w, l))
    z = tuple(-h / 2 + t / 2 + k * (h - t) / (boards - 1) for k in range(boards))
    return ShelfLayout((w, l, h), t, z)


def _shelf_boards(dimensions: tuple[float, float, float]) -> tuple[Surface, ...]:
    layout = shelf_layout(dimensions)
    return tuple(layout.board(k) for k in range(len(layout.board_z)))


def _table_top(dimensions: tuple[float, float, float]) -> tuple[Surface, ...]:
    w, l, h = (float(v) for v in dimensions)
    return (Surface((0.0, 0.0, h / 2), w, l, None),)


ASSET_SURFACES: dict[str, dict[str, Callable[[tuple[float, float, float]], tuple[Surface, ...]]]] = {
    "shelf": {"boards": _shelf_boards},
    "table": {"tabletop": _table_top},
}
"""Per furniture asset (model name): its named support surfaces, each a list fitted to the box."""


def asset_surfaces(model: str | None, name: str, dimensions: tuple[float, float, float]) -> tuple[Surface, ...] | None:
    """Surfaces `name` of asset `model` fitted to the box, or None when the asset has none of that name."""
    recipe = ASSET_SURFACES.get(model or "", {}).get(name)
    return None if recipe is None else recipe(tuple(float(v) for v in dimensions))  # type: ignore[arg-type]
