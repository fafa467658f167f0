"""Uniform points in convex polygons given as half-planes (prsc/geometry/polygon.py).

A KS test per coordinate (and on x + y) against rejection sampling from the bounding square
at fixed seeds: p >= 0.01 for the polygon itself, p < 1e-6 against the uncut square, so the
test can fail. Empty and degenerate polygons are reported, never drawn."""

from __future__ import annotations

import numpy as np
from scipy.stats import ks_2samp

from prsc.geometry.polygon import polygon_points

# The square [-1, 1]^2 cut by x + y <= 0.5 and x >= -0.8: a pentagon.
PENTAGON = np.array([[1, 0, 1], [-1, 0, 1], [0, 1, 1], [0, -1, 1], [1, 1, 0.5], [-1, 0, 0.8]], dtype=float)
N = 20_000


def _reference(rows: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    q = rng.uniform(-1, 1, (8 * N, 2))
    return q[np.all(q @ rows[:, :2].T <= rows[:, 2], axis=1)][:N]


def _pvalues(a: np.ndarray, b: np.ndarray) -> list[float]:
    return [ks_2samp(a[:, 0], b[:, 0]).pvalue, ks_2samp(a[:, 1], b[:, 1]).pvalue, ks_2samp(a.sum(axis=1), b.sum(axis=1)).pvalue]


def test_points_are_uniform_on_the_polygon_and_the_test_sees_another_region():
    rng = np.random.default_rng(3)
    points, has_area = polygon_points(np.broadcast_to(PENTAGON, (N,) + PENTAGON.shape), rng.random((N, 3)))
    assert has_area.all()
    assert np.all(points @ PENTAGON[:, :2].T <= PENTAGON[:, 2] + 1e-12)
    assert min(_pvalues(points, _reference(PENTAGON, rng))) >= 0.01
    assert min(_pvalues(points, _reference(PENTAGON[:4], rng))) < 1e-6  # the square without its cuts


def test_each_polygon_reads_its_own_rows_and_uniforms():
    rng = np.random.default_rng(4)
    rows = np.stack([PENTAGON, PENTAGON * [1, 1, 2]])  # the second polygon is the first scaled by 2
    u = np.repeat(rng.random((1, 3)), 2, axis=0)
    both, _ = polygon_points(rows, u)
    alone, _ = polygon_points(rows[1:], u[1:])
    assert np.array_equal(both[1], alone[0])
    assert np.allclose(both[1], 2 * both[0], atol=1e-12)  # the same uniforms, the same place in it


def test_empty_and_flat_polygons_have_no_area():
    empty = np.array([[1, 0, 1], [-1, 0, -2], [0, 1, 1], [0, -1, 1]], dtype=float)  # x <= 1 and x >= 2
    flat = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 1], [0, -1, 1]], dtype=float)  # x = 0: a segment
    _, has_area = polygon_points(np.stack([empty, flat]), np.full((2, 3), 0.5))
    assert not has_area.any()
