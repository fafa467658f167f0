"""A table: a top slab on four square legs, filling the object's box."""

from __future__ import annotations

from prsc.assets.parts import Part, box


def table_parts(dimensions: tuple[float, float, float]) -> tuple[Part, ...]:
    """Top and legs of a table fitted to `dimensions` (width, length, height)."""
    w, l, h = dimensions
    top = min(max(0.06 * h, 0.02), 0.06, 0.5 * h)
    leg = min(max(0.06 * min(w, l), 0.03), 0.08, 0.25 * min(w, l))
    leg_h = h - top
    parts = [box("top", (w, l, top), (0.0, 0.0, h / 2 - top / 2))]
    z_leg = -h / 2 + leg_h / 2
    for name, sx, sy in (("leg_fl", -1, 1), ("leg_fr", 1, 1), ("leg_bl", -1, -1), ("leg_br", 1, -1)):
        parts.append(box(name, (leg, leg, leg_h), (sx * (w / 2 - leg / 2), sy * (l / 2 - leg / 2), z_leg)))
    return tuple(parts)
