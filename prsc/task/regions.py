"""Signed distances to the convex prisms of prsc/task/terms.py (positive inside), exact: a prism is a
polygon times an interval, so the distance from outside is the hypot of the two distances."""

from __future__ import annotations

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


def polygon_signed_distance(region: Region, q: np.ndarray) -> np.ndarray:
    """Signed distance of points q (m, 2) to the footprint polygon: inside positive."""
    normals = np.asarray(region.normals, dtype=float)
    offsets = np.asarray(region.offsets, dtype=float)
    margins = offsets[None, :] - q @ normals.T  # (m, k)
    inside = margins.min(axis=1)
    vertices = polygon_vertices(region)
    start, end = vertices, np.roll(vertices, -1, axis=0)
    edge = end - start
    t = np.clip(np.einsum("mkd,kd->mk", q[:, None, :] - start[None], edge) / np.einsum("kd,kd->k", edge, edge), 0.0, 1.0)
    nearest = start[None] + t[..., None] * edge[None]
    outside = np.linalg.norm(q[:, None, :] - nearest, axis=2).min(axis=1)
    return np.where(inside >= 0.0, inside, -outside)


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
