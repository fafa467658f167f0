"""Seating furniture fitted to the object's box."""

from __future__ import annotations

from prsc.assets.parts import Part, box
from prsc.geometry.furniture_surfaces import SHELF_BOARDS, shelf_layout


def chair_parts(dimensions: tuple[float, float, float]) -> tuple[Part, ...]:
    """A chair facing +y: four legs, a seat at half height and a backrest at the back (-y)."""
    w, l, h = dimensions
    seat_z = 0.5 * h
    seat = min(max(0.05 * h, 0.02), 0.05)
    leg = min(max(0.08 * min(w, l), 0.02), 0.05)
    back = min(leg, 0.1 * l)
    leg_h = seat_z - seat
    parts = [box("seat", (w, l, seat), (0.0, 0.0, -h / 2 + seat_z - seat / 2))]
    for name, sx, sy in (("leg_fl", -1, 1), ("leg_fr", 1, 1), ("leg_bl", -1, -1), ("leg_br", 1, -1)):
        parts.append(box(name, (leg, leg, leg_h), (sx * (w / 2 - leg / 2), sy * (l / 2 - leg / 2), -h / 2 + leg_h / 2)))
    back_h = h - seat_z
    parts.append(box("backrest", (w, back, back_h), (0.0, -l / 2 + back / 2, h / 2 - back_h / 2)))
    return tuple(parts)


def shelf_parts(dimensions: tuple[float, float, float], boards: int = SHELF_BOARDS) -> tuple[Part, ...]:
    """A bookshelf open towards +y: two sides, a back panel and `boards` evenly spaced boards
    (prsc.geometry.furniture_surfaces.shelf_layout: the same numbers `on shelf.boards[k]` rests on)."""
    layout = shelf_layout(dimensions, boards)
    w, l, h = layout.dimensions
    t = layout.thickness
    parts = [
        box("side_left", (t, l, h), (-w / 2 + t / 2, 0.0, 0.0)),
        box("side_right", (t, l, h), (w / 2 - t / 2, 0.0, 0.0)),
        box("back", (w - 2 * t, t, h), (0.0, -l / 2 + t / 2, 0.0)),
    ]
    for k, z in enumerate(layout.board_z):
        parts.append(box(f"board_{k}", (w - 2 * t, l - t, t), (0.0, t / 2, z)))
    return tuple(parts)
