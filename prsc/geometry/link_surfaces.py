"""Where things rest on or in a link of an articulated asset (docs/assets.md, "Links"): from the
boxes of the link's collision geometry, in the link's frame.

Every box's top face is a candidate. What rises from a face's level over part of it (a wall)
cuts the face back to the rectangle about its centre that stays clear; a box over the face's
centre covers it. The **support surface** (`on`) is the clear face of largest area, the higher
one on a tie (a cabinet's top, not its bottom panel). A face walled on all four sides is a
floor; the **interior** (`in`) is the largest such floor, within its walls. This is what
scene_synthesizer's support and containment labels find, as exact rectangles.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Sequence

Box = tuple[tuple[float, float, float], tuple[float, float, float]]

TOLERANCE = 1e-6  # m: boxes that meet within this are touching


@dataclass(frozen=True)
class Face:
    """An upward rectangle in the link frame: x in [x_low, x_high], y in [y_low, y_high] at height z."""

    x_low: float
    x_high: float
    y_low: float
    y_high: float
    z: float
    wall_top: float | None = None  # a floor: the lowest top of its four walls

    @property
    def centre(self) -> tuple[float, float, float]:
        """The rectangle's centre."""
        return ((self.x_low + self.x_high) / 2, (self.y_low + self.y_high) / 2, self.z)

    @property
    def size(self) -> tuple[float, float]:
        """(width along x, length along y)."""
        return (self.x_high - self.x_low, self.y_high - self.y_low)

    @property
    def area(self) -> float:
        """Width times length."""
        return self.size[0] * self.size[1]


@dataclass(frozen=True)
class LinkSurfaces:
    """The support surface and the interior of one link (None where it has none)."""

    support: Face | None
    interior: Face | None


def _clear_face(top: Box, boxes: Sequence[Box]) -> Face | None:
    """The top face of `top` cut back by what rises from its level over it, or None when covered."""
    (x0, y0, _), (x1, y1, z) = top
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    walls: dict[str, float] = {}
    for (bx0, by0, bz0), (bx1, by1, bz1) in boxes:
        if bz1 <= z + TOLERANCE:
            continue  # at or below the face
        if bz0 > z + TOLERANCE:
            continue  # above it, not standing on it: free space up to there (a board above)
        apart = (x0 - bx1, bx0 - x1, y0 - by1, by0 - y1)  # gaps on the -x, +x, -y, +y sides
        if max(apart) > TOLERANCE:
            continue  # beside it, not touching
        if max(apart) >= -TOLERANCE:  # touching an edge: a wall on that side, nothing to cut
            if (by0 < y1 and by1 > y0) or (bx0 < x1 and bx1 > x0):
                side = ("-x", "+x", "-y", "+y")[apart.index(max(apart))]
                walls[side] = min(walls.get(side, bz1), bz1)
            continue
        cuts = []  # (side, new bound, area kept)
        if bx0 >= cx:
            cuts.append(("+x", bx0, (bx0 - x0) * (y1 - y0)))
        if bx1 <= cx:
            cuts.append(("-x", bx1, (x1 - bx1) * (y1 - y0)))
        if by0 >= cy:
            cuts.append(("+y", by0, (x1 - x0) * (by0 - y0)))
        if by1 <= cy:
            cuts.append(("-y", by1, (x1 - x0) * (y1 - by1)))
        if not cuts:
            return None  # over the centre
        side, bound, _ = max(cuts, key=lambda cut: cut[2])
        if side == "+x":
            x1 = bound
        elif side == "-x":
            x0 = bound
        elif side == "+y":
            y1 = bound
        else:
            y0 = bound
        walls[side] = min(walls.get(side, bz1), bz1)
    if x1 - x0 <= TOLERANCE or y1 - y0 <= TOLERANCE:
        return None
    wall_top = min(walls.values()) if len(walls) == 4 else None
    return Face(x0, x1, y0, y1, z, wall_top)


@lru_cache(maxsize=64)
def link_surfaces(boxes: tuple[Box, ...]) -> LinkSurfaces:
    """The support surface and interior of a link made of `boxes` (its collision geometry;
    cached: the lowering's check and the expression compiler both ask for it)."""
    faces = [face for box in boxes if (face := _clear_face(box, boxes)) is not None]
    rank = lambda face: (round(face.area, 9), face.z)  # noqa: E731 - largest, then highest
    support = max(faces, key=rank, default=None)
    floors = [face for face in faces if face.wall_top is not None]
    return LinkSurfaces(support, max(floors, key=rank, default=None))
