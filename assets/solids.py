"""Solid objects to pick up: cube, cylinder, bottle."""

from __future__ import annotations

from prsc.assets.parts import Part, box, cylinder


def cube_parts(dimensions: tuple[float, float, float]) -> tuple[Part, ...]:
    """A solid box filling the object's box."""
    return (box("box", dimensions),)


def cylinder_parts(dimensions: tuple[float, float, float]) -> tuple[Part, ...]:
    """A solid z-axis cylinder inscribed in the object's box."""
    w, l, h = dimensions
    return (cylinder("cylinder", min(w, l) / 2, h),)


def bottle_parts(dimensions: tuple[float, float, float]) -> tuple[Part, ...]:
    """A bottle: a body cylinder (70% of the height) and a neck of 35% of its radius."""
    w, l, h = dimensions
    r = min(w, l) / 2
    body_h = 0.7 * h
    neck_h = h - body_h
    return (
        cylinder("body", r, body_h, (0.0, 0.0, -h / 2 + body_h / 2)),
        cylinder("neck", 0.35 * r, neck_h, (0.0, 0.0, h / 2 - neck_h / 2)),
    )
