"""Uniform points in many small convex polygons at once, each given as half-planes.

Polygon i is {q : alpha q_x + beta q_y <= gamma for every row}. Its vertices are the
pairwise intersections of the rows' lines that meet every row; sorted by angle about their
mean they bound the polygon, and a fan from the first one triangulates it. A triangle is
picked by area, then a point in it by the square-root rule (Osada et al., "Shape
distributions", 2002), so the point is uniform on the polygon. Everything is elementwise
per polygon: polygon i's point depends on its rows and its uniforms alone.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

# A vertex may violate a row by this much (relative to the row's scale) and still count:
# vertices lie on two rows, up to rounding.
_SLACK = 1e-12
# Lines meeting at a smaller |sine| than this are taken as parallel (no vertex).
_PARALLEL = 1e-12


def polygon_points(rows: NDArray[np.float64], u: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Points uniform on each polygon: rows (n, m, 3) of (alpha, beta, gamma), uniforms (n, 3).

    Returns (points (n, 2), whether the polygon has an area: elsewhere the point is
    meaningless)."""
    alpha, beta, gamma = rows[:, :, 0], rows[:, :, 1], rows[:, :, 2]
    n, m = alpha.shape
    i, j = np.triu_indices(m, 1)
    det = alpha[:, i] * beta[:, j] - alpha[:, j] * beta[:, i]
    scale = np.hypot(alpha[:, i], beta[:, i]) * np.hypot(alpha[:, j], beta[:, j])
    meets = np.abs(det) > _PARALLEL * np.maximum(scale, 1e-300)
    safe = np.where(meets, det, 1.0)
    x = (gamma[:, i] * beta[:, j] - gamma[:, j] * beta[:, i]) / safe
    y = (alpha[:, i] * gamma[:, j] - alpha[:, j] * gamma[:, i]) / safe
    slack = _SLACK * (np.abs(gamma) + np.hypot(alpha, beta))[:, :, None]
    inside = np.all(alpha[:, :, None] * x[:, None, :] + beta[:, :, None] * y[:, None, :] <= gamma[:, :, None] + slack, axis=1)
    inside &= meets
    count = inside.sum(axis=1)
    weight = inside.astype(float)
    cx = (x * weight).sum(axis=1) / np.maximum(count, 1)
    cy = (y * weight).sum(axis=1) / np.maximum(count, 1)
    angle = np.where(inside, np.arctan2(y - cy[:, None], x - cx[:, None]), np.inf)
    order = np.argsort(angle, axis=1)
    vx, vy = np.take_along_axis(x, order, axis=1), np.take_along_axis(y, order, axis=1)
    k = np.arange(1, vx.shape[1] - 1)
    # Fan triangles (v0, v_k, v_k+1) for k + 1 < count: twice their areas.
    ax, ay = vx[:, k] - vx[:, :1], vy[:, k] - vy[:, :1]
    bx, by = vx[:, k + 1] - vx[:, :1], vy[:, k + 1] - vy[:, :1]
    twice = np.where(k[None, :] + 1 < count[:, None], np.abs(ax * by - ay * bx), 0.0)
    cumulative = np.cumsum(twice, axis=1)
    total = cumulative[:, -1] if cumulative.shape[1] else np.zeros(n)
    has_area = total > 0.0
    pick = np.minimum((cumulative < (u[:, :1] * total[:, None])).sum(axis=1), max(cumulative.shape[1] - 1, 0))
    root = np.sqrt(u[:, 1])
    wa, wb = root * (1.0 - u[:, 2]), root * u[:, 2]
    rows_ = np.arange(n)
    px = vx[:, 0] + wa * ax[rows_, pick] + wb * bx[rows_, pick] if len(k) else vx[:, 0]
    py = vy[:, 0] + wa * ay[rows_, pick] + wb * by[rows_, pick] if len(k) else vy[:, 0]
    return np.stack([px, py], axis=1), has_area
