"""Collision checks between a candidate box and the boxes placed so far.

Broad phase by axis-aligned bounding boxes in plain Python floats, exact oriented-box test
(prsc.geometry.obb, all 15 axes) only when the AABBs overlap. The broad phase is
conservative with the same contact tolerance: the projections of two boxes on a world
axis overlap no more than their AABBs do, and the smallest overlap over the 15 SAT axes is
the smallest over all directions, so AABBs overlapping by <= tol on some axis mean no
collision. Resting contact (`on`) overlaps by 0 and is never a collision.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from prsc.geometry.boxes import Box
from prsc.geometry.obb import CONTACT_TOL, axis_aligned, boxes_collide, minkowski_obstacle, pair_overlaps, upright_overlaps
from prsc.geometry.polytope import Polytope


class PlacedBox:
    """A placed object's box, with its AABB half extents for the broad phase."""

    __slots__ = ("name", "index", "center", "reach", "allow", "aligned", "_center", "_rotation", "_half", "_box")

    def __init__(
        self, name: str, index: int, center: np.ndarray, rotation: np.ndarray, half: np.ndarray, allow: bool
    ) -> None:
        self.name = name
        self.index = index
        self.allow = allow
        self._center, self._rotation, self._half = center, rotation, half
        self.center: tuple[float, float, float] = tuple(center.tolist())  # type: ignore[assignment]
        self.reach: tuple[float, float, float] = tuple((np.abs(rotation) @ half).tolist())  # type: ignore[assignment]
        self.aligned = axis_aligned(rotation)  # its box is its axis-aligned bounding box
        self._box: Box | None = None

    @property
    def box(self) -> Box:
        """The oriented box (built on first use: only the narrow phase needs it)."""
        if self._box is None:
            self._box = Box(self._center, self._rotation, self._half)
        return self._box


def aabb_reach(rotation: np.ndarray | None, half: np.ndarray, mode: str = "exact") -> tuple[float, float, float]:
    """AABB half extents of a box (or a bound when its rotation is not known yet)."""
    if mode == "exact" and rotation is not None:
        return tuple((np.abs(rotation) @ half).tolist())
    if mode == "yaw":
        r = float(np.hypot(half[0], half[1]))
        return (r, r, float(half[2]))
    r = float(np.linalg.norm(half))
    return (r, r, r)


def inscribed_half(half: np.ndarray, mode: str) -> np.ndarray:
    """Half extents of an axis-aligned box inside the object's box for every rotation it may get.

    "yaw": the footprint always holds the disc of radius min(w, l)/2, so the square of
    half side r/sqrt(2); the height is unchanged. "free": the inscribed ball's cube.
    """
    if mode == "yaw":
        r = float(min(half[0], half[1])) / np.sqrt(2.0)
        return np.array([r, r, float(half[2])])
    r = float(np.min(half)) / np.sqrt(3.0)
    return np.array([r, r, r])


def near(
    placed: list[PlacedBox], lo: np.ndarray, hi: np.ndarray, reach: tuple[float, float, float], tol: float = CONTACT_TOL,
    containers: tuple[int, ...] = (),
) -> list[PlacedBox]:
    """Placed boxes that a box with AABB half extents `reach`, centred anywhere in [lo, hi], could hit
    (the `containers` it rests inside excepted: their walls, not their boxes, bound it)."""
    lx, ly, lz = lo.tolist()
    hx, hy, hz = hi.tolist()
    rx, ry, rz = reach
    out = []
    for q in placed:
        if q.allow or q.index in containers:
            continue
        (cx, cy, cz), (ex, ey, ez) = q.center, q.reach
        if (
            cx + ex - tol > lx - rx and cx - ex + tol < hx + rx
            and cy + ey - tol > ly - ry and cy - ey + tol < hy + ry
            and cz + ez - tol > lz - rz and cz - ez + tol < hz + rz
        ):
            out.append(q)
    return out


def first_hit(
    candidates: list[PlacedBox], center: np.ndarray, rotation: np.ndarray, half: np.ndarray,
    reach: tuple[float, float, float], tol: float = CONTACT_TOL,
) -> PlacedBox | None:
    """The first candidate the box collides with, or None."""
    if not candidates:
        return None
    px, py, pz = center.tolist()
    rx, ry, rz = reach
    box = None
    aligned: bool | None = None
    for q in candidates:
        (cx, cy, cz), (ex, ey, ez) = q.center, q.reach
        if abs(px - cx) >= rx + ex - tol or abs(py - cy) >= ry + ey - tol or abs(pz - cz) >= rz + ez - tol:
            continue
        if aligned is None:
            aligned = axis_aligned(rotation)
        if aligned and q.aligned:
            return q  # two axis-aligned boxes overlapping by more than tol on every world axis collide
        if box is None:
            box = Box(center, rotation, half)
        if boxes_collide(box, q.box, tol):
            return q
    return None


def obstacles_for(candidates: list[PlacedBox], rotation: np.ndarray, half: np.ndarray) -> list[Polytope]:
    """Minkowski obstacles: the centres where the new box would hit each candidate."""
    aligned = axis_aligned(rotation)
    return [minkowski_obstacle(q.box, rotation, half, CONTACT_TOL, aligned=aligned and q.aligned) for q in candidates]


def apart(lo_a: np.ndarray, hi_a: np.ndarray, reach_a: Any, lo_b: np.ndarray, hi_b: np.ndarray, reach_b: Any,
          tol: float = CONTACT_TOL) -> bool:
    """Whether two boxes (axis-aligned half extents reach_a, reach_b) centred anywhere in [lo_a, hi_a] and
    [lo_b, hi_b] never overlap by more than tol on some world axis: `near`'s broad phase over every scene."""
    gap = np.asarray(reach_a) + np.asarray(reach_b) - tol
    return bool(np.any(hi_a + gap <= lo_b) or np.any(hi_b + gap <= lo_a))


def collide_pairs(pa: np.ndarray, ra: np.ndarray, ha: np.ndarray, pb: np.ndarray, rb: np.ndarray, hb: np.ndarray,
                  reach: np.ndarray, upright: bool, aligned: bool = False) -> np.ndarray:
    """Which of n box pairs collide, as `first_hit` decides one: boxes whose axis-aligned boxes (summed half
    extents `reach`) overlap by more than the tolerance on every world axis, then the SAT (5 axes when both
    boxes only yaw); the broad phase alone decides for two axis-aligned boxes. Centres (n, 3); rotations and
    half extents (n, 3, 3) and (n, 3), or broadcastable to them."""
    close = np.flatnonzero(np.all(np.abs(pa - pb) < reach - CONTACT_TOL, axis=1))
    hit = np.zeros(len(pa), dtype=bool)
    if aligned or not len(close):
        hit[close] = True
        return hit
    n = len(pa)
    ra, ha = np.broadcast_to(ra, (n, 3, 3))[close], np.broadcast_to(ha, (n, 3))[close]
    rb, hb = np.broadcast_to(rb, (n, 3, 3))[close], np.broadcast_to(hb, (n, 3))[close]
    overlaps = upright_overlaps if upright else pair_overlaps
    hit[close] = overlaps(pa[close], ra, ha, pb[close], rb, hb) > CONTACT_TOL
    return hit
