"""Signed distances to the convex prisms of prsc/task/terms.py (positive inside), exact: a prism is a
polygon times an interval, so the distance from outside is the hypot of the two distances."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from prsc.task.terms import Region


def polygon_vertices(region: Region) -> np.ndarray:
    """The footprint's vertices (k, 2) in counter-clockwise order (rows n . q <= c, unit n)."""
    normals = np.asarray(region.normals, dtype=float)
    offsets = np.asarray(region.offsets, dtype=float)
    order = np.argsort(np.arctan2(normals[:, 1], normals[:, 0]))
    normals, offsets = normals[order], offsets[order]
    nxt = np.roll(np.arange(len(offsets)), -1)
    a = np.stack([normals, normals[nxt]], axis=1)  # (k, 2, 2): each vertex joins an edge and the next
    return np.linalg.solve(a, np.stack([offsets, offsets[nxt]], axis=1)[..., None])[..., 0]


@dataclass(frozen=True)
class _Polygon:
    """A footprint's rows and edges as arrays, computed once per region (evaluated at every step)."""

    normals: np.ndarray  # (k, 2)
    offsets: np.ndarray  # (k,)
    start: np.ndarray  # (k, 2): each edge's first vertex
    edge: np.ndarray  # (k, 2)
    length2: np.ndarray  # (k,)
    rows: tuple[tuple[float, float, float], ...]  # (nx, ny, c) per row, as floats for one point
    edges: tuple[tuple[float, float, float, float, float], ...]  # (sx, sy, ex, ey, length2) per edge


@functools.lru_cache(maxsize=256)
def prepared_polygon(region: Region) -> _Polygon:
    """The footprint of a region as arrays (cached: an evaluator prepares each region once)."""
    return _prepare(region)


def _prepare(region: Region) -> _Polygon:
    vertices = polygon_vertices(region)
    edge = np.roll(vertices, -1, axis=0) - vertices
    length2 = np.einsum("kd,kd->k", edge, edge)
    return _Polygon(np.asarray(region.normals, dtype=float), np.asarray(region.offsets, dtype=float), vertices, edge,
                    length2, tuple((float(n[0]), float(n[1]), float(c)) for n, c in zip(region.normals, region.offsets)),
                    tuple((*map(float, v), *map(float, e), float(l2)) for v, e, l2 in zip(vertices, edge, length2)))


def polygon_signed_distance(region: Region | _Polygon, q: np.ndarray) -> np.ndarray:
    """Signed distance of points q (m, 2) to the footprint polygon: inside positive."""
    poly = region if isinstance(region, _Polygon) else prepared_polygon(region)
    inside = (poly.offsets[None, :] - q @ poly.normals.T).min(axis=1)  # exact inside a convex polygon
    if np.all(inside >= 0.0):
        return inside
    relative = q[:, None, :] - poly.start[None]
    t = np.clip(np.einsum("mkd,kd->mk", relative, poly.edge) / poly.length2, 0.0, 1.0)
    gaps = relative - t[..., None] * poly.edge[None]
    outside = np.sqrt(np.einsum("mkd,mkd->mk", gaps, gaps).min(axis=1))
    return np.where(inside >= 0.0, inside, -outside)


def point_polygon_distance(poly: _Polygon, x: float, y: float) -> float:
    """polygon_signed_distance of one point, in plain floats (the evaluator's per-step path: comparisons
    instead of min() and max() calls, the same numbers)."""
    inside = math.inf
    for nx, ny, c in poly.rows:
        margin = c - nx * x - ny * y
        if margin < inside:
            inside = margin
    if inside >= 0.0:
        return inside
    best = math.inf
    for sx, sy, ex, ey, length2 in poly.edges:
        rx, ry = x - sx, y - sy
        t = (rx * ex + ry * ey) / length2
        t = 0.0 if t < 0.0 else 1.0 if t > 1.0 else t
        squared = (rx - t * ex) ** 2 + (ry - t * ey) ** 2
        if squared < best:
            best = squared
    return -best ** 0.5


def prism_signed_distance(region: Region, points: np.ndarray) -> np.ndarray:
    """Signed distance of points (m, 3), in the region's frame, to the prism: inside positive."""
    flat = polygon_signed_distance(region, points[:, :2])
    z = points[:, 2]
    vertical = np.minimum(z - region.low, region.high - z)  # inside the slab: positive
    inside = np.minimum(flat, vertical)
    outside = np.hypot(np.minimum(flat, 0.0), np.minimum(vertical, 0.0))
    return np.where((flat >= 0.0) & (vertical >= 0.0), inside, -outside)


def box_region(dimensions: tuple[float, float, float]) -> Region:
    """The object's whole box as a region."""
    w, l, h = dimensions
    return Region(((1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)), (w / 2, w / 2, l / 2, l / 2), -h / 2, h / 2)


def box_corners(dimensions: tuple[float, float, float]) -> np.ndarray:
    """The 8 corners (8, 3) of a box centred at the origin."""
    half = np.asarray(dimensions, dtype=float) / 2
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
    return signs * half
