"""Exact sampler: measures, containment, determinism and chi-square uniformity (p > 0.001)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chisquare

from prsc.geometry.boxes import Box
from prsc.geometry.exceptions import EmptyRegionError, UnboundedRegionError
from prsc.geometry.polytope import Polytope
from prsc.geometry.rotations import compat_euler_to_matrix, rot_z
from prsc.geometry.uniform_sampling import UniformSampler, prepare_sampler, union_sampler

P_MIN = 1e-3
R = compat_euler_to_matrix(0.4, 0.3, -0.2)


def _chi2_uniform_cells(local: np.ndarray, lo, hi, cells: int) -> float:
    """p-value of the counts of points (n, d) over a cells^d grid of [lo, hi] being uniform."""
    idx = np.floor((local - lo) / (np.asarray(hi) - lo) * cells).astype(int)
    assert idx.min() >= 0 and idx.max() < cells
    flat = np.ravel_multi_index(idx.T, (cells,) * local.shape[1])
    counts = np.bincount(flat, minlength=cells ** local.shape[1])
    return chisquare(counts).pvalue


def test_rotated_eroded_box_is_uniform_3d():
    # Eroding a rotated box by a box of the same rotation gives the smaller box: uniform in
    # its local coordinates.
    c = np.array([0.2, -0.1, 0.8])
    region = Polytope.from_box(Box(c, R, [0.6, 0.4, 0.3])).erode_by_box(R, [0.1, 0.15, 0.05])
    s = prepare_sampler(region)
    assert s.dim == 3
    assert s.measure == pytest.approx(1.0 * 0.5 * 0.5, rel=1e-12)
    x = s.sample(np.random.default_rng(1), 200_000)
    local = (x - c) @ R
    assert np.all(np.abs(local) <= [0.5 + 1e-12, 0.25 + 1e-12, 0.25 + 1e-12])
    assert _chi2_uniform_cells(local, [-0.5, -0.25, -0.25], [0.5, 0.25, 0.25], 5) > P_MIN


def test_general_eroded_polytope_is_uniform_over_cells():
    # Different rotations: the eroded set is a general polytope. Expected cell counts are the
    # exact volumes of region ∩ cell; the volume itself is checked against Monte Carlo.
    region = Polytope.from_box(Box([0, 0, 0.5], R, [0.7, 0.5, 0.4])).erode_by_box(rot_z(0.9), [0.1, 0.2, 0.05])
    region = region.intersect(Polytope.halfspace([1, 1, 0], 0.3))
    s = prepare_sampler(region)
    rng = np.random.default_rng(2)
    lo, hi = s.bounds()
    mc = rng.uniform(lo, hi, size=(400_000, 3))
    frac = region.contains(mc, tol=0).mean()
    assert s.measure == pytest.approx(frac * np.prod(hi - lo), rel=0.01)
    cells = 3
    edges = [np.linspace(lo[i], hi[i], cells + 1) for i in range(3)]
    expected = []
    for i in range(cells):
        for j in range(cells):
            for k in range(cells):
                cell = Polytope.from_rows(
                    np.vstack([np.eye(3), -np.eye(3)]),
                    [edges[0][i + 1], edges[1][j + 1], edges[2][k + 1], -edges[0][i], -edges[1][j], -edges[2][k]],
                )
                try:
                    expected.append(prepare_sampler(region.intersect(cell)).measure)
                except EmptyRegionError:
                    expected.append(0.0)
    expected = np.array(expected)
    assert expected.sum() == pytest.approx(s.measure, rel=1e-9)
    x = s.sample(rng, 200_000)
    assert region.contains(x, tol=1e-9).all()
    idx = np.clip(np.floor((x - lo) / (hi - lo) * cells).astype(int), 0, cells - 1)
    counts = np.bincount(np.ravel_multi_index(idx.T, (cells,) * 3), minlength=cells**3)
    nz = expected > 0
    assert counts[~nz].sum() == 0
    assert chisquare(counts[nz], expected[nz] / expected[nz].sum() * len(x)).pvalue > P_MIN


def test_polygon_on_a_rotated_plane_is_uniform_2d():
    # A unit square on a tilted plane, cut by its diagonal u + v <= 1 (local coordinates):
    # a triangle. On a 6 x 6 grid, cells below the diagonal have weight 1, on it 1/2.
    c = np.array([0.5, 0.5, 1.0])
    rect = Polytope.from_rectangle(c, R, 1.0, 1.0)
    n = R[:, 0] + R[:, 1]  # u + v <= 1 with u, v in [-0.5, 0.5] about c: n.(p - c) <= 0
    tri = rect.intersect(Polytope.halfspace(n, n @ c))
    s = prepare_sampler(tri)
    assert s.dim == 2 and s.measure == pytest.approx(0.5, rel=1e-12)
    x = s.sample(np.random.default_rng(3), 200_000)
    local = (x - c) @ R
    assert np.max(np.abs(local[:, 2])) < 1e-12  # on the plane
    cells = 6
    idx = np.floor((local[:, :2] + 0.5) * cells).astype(int)
    weights = np.zeros((cells, cells))
    for i in range(cells):
        for j in range(cells):
            weights[i, j] = 1.0 if i + j < cells - 1 else (0.5 if i + j == cells - 1 else 0.0)
    counts = np.zeros((cells, cells))
    np.add.at(counts, (idx[:, 0], idx[:, 1]), 1)
    nz = weights > 0
    assert counts[~nz].sum() == 0
    assert chisquare(counts[nz], weights[nz] / weights[nz].sum() * len(x)).pvalue > P_MIN


def test_segment_is_uniform_1d():
    # The intersection of two planes inside a box: a segment along the line.
    box = Polytope.from_box(Box([0, 0, 0], R, [0.5, 0.5, 0.5]))
    line = box.intersect(Polytope.plane([0, 0, 1], 0.1), Polytope.plane([1, 1, 0], 0.05))
    s = prepare_sampler(line)
    assert s.dim == 1
    lo, hi = s.simplices[0, 0], s.simplices[0, 1]
    assert s.measure == pytest.approx(np.linalg.norm(hi - lo), rel=1e-12)
    x = s.sample(np.random.default_rng(4), 100_000)
    assert line.contains(x, tol=1e-9).all()
    t = (x - lo) @ (hi - lo) / np.dot(hi - lo, hi - lo)
    assert _chi2_uniform_cells(t[:, None], [0.0], [1.0 + 1e-12], 20) > P_MIN


def test_point_region_samples_the_point():
    p = Polytope.from_rows(np.zeros((0, 3)), [], C=np.eye(3), d=[1, 2, 3])
    s = prepare_sampler(p)
    assert s.dim == 0 and s.measure == 1.0
    assert np.allclose(s.sample(np.random.default_rng(0), 5), [[1, 2, 3]] * 5)
    assert np.allclose(s.sample_one(np.random.default_rng(0)), [1, 2, 3])


def test_sample_one_reads_the_same_stream_as_batch():
    s = prepare_sampler(Polytope.from_box(Box([0, 0, 0], R, [0.3, 0.2, 0.1])))
    a, b = np.random.default_rng(7), np.random.default_rng(7)
    batch = s.sample(a, 50)
    singles = np.array([s.sample_one(b) for _ in range(50)])
    assert np.allclose(batch, singles, atol=1e-14)
    assert np.array_equal(a.random(3), b.random(3))  # same number of draws consumed


def test_same_seed_same_samples():
    s = prepare_sampler(Polytope.from_box(Box([0, 0, 0], R, [0.3, 0.2, 0.1])))
    assert np.array_equal(s.sample(np.random.default_rng(5), 100), s.sample(np.random.default_rng(5), 100))


def test_empty_and_unbounded_regions():
    with pytest.raises(EmptyRegionError):
        prepare_sampler(Polytope.halfspace([1, 0, 0], 0.0).intersect(Polytope.halfspace([-1, 0, 0], -1.0)))
    with pytest.raises(UnboundedRegionError):
        prepare_sampler(Polytope.halfspace([0, 0, 1], 0.0))
    with pytest.raises(UnboundedRegionError):
        prepare_sampler(Polytope.plane([0, 0, 1], 0.0))


def test_union_sampler_weights_by_measure():
    a = prepare_sampler(Polytope.from_box(Box([0, 0, 0], np.eye(3), [0.5, 0.5, 0.5])))
    b = prepare_sampler(Polytope.from_box(Box([2, 0, 0], np.eye(3), [0.5, 0.5, 1.0])))
    u = union_sampler([a, b])
    assert u.measure == pytest.approx(3.0)
    x = u.sample(np.random.default_rng(6), 30_000)
    frac = np.mean(x[:, 0] > 1.0)
    assert abs(frac - 2 / 3) < 4 * np.sqrt(2 / 9 / len(x))


def test_slivers_are_dropped_and_no_simplices_is_empty():
    with pytest.raises(EmptyRegionError):
        UniformSampler(np.zeros((0, 4, 3)), np.zeros(0))
    s = UniformSampler.from_simplices(np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]]], float))
    assert len(s.simplices) == 1 and s.measure == pytest.approx(1 / 6)


def test_thin_and_many_row_regions():
    # Regions with many redundant and nearly parallel rows still decompose exactly.
    rng = np.random.default_rng(8)
    n = rng.normal(size=(40, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    ball_ish = Polytope.from_rows(n, np.ones(40))
    s = prepare_sampler(ball_ish)
    lo, hi = s.bounds()
    mc = rng.uniform(lo, hi, size=(400_000, 3))
    assert s.measure == pytest.approx(ball_ish.contains(mc, tol=0).mean() * np.prod(hi - lo), rel=0.01)
    slab = Polytope.from_box(Box([0, 0, 0], R, [0.5, 0.5, 1e-6]))
    s = prepare_sampler(slab)
    assert s.dim == 3 and s.measure == pytest.approx(2e-6, rel=1e-6)


def test_fast_path_and_lp_path_agree():
    from prsc.geometry.affine import reduce_affine
    from prsc.geometry.uniform_sampling import simplices_of

    regions = [
        Polytope.from_box(Box([0, 0, 0.5], R, [0.7, 0.5, 0.4])).erode_by_box(rot_z(0.9), [0.1, 0.2, 0.05]),
        Polytope.from_rectangle([0, 0, 1], R, 1.0, 0.6).intersect(Polytope.halfspace([1, 0, 0], 0.1)),
        Polytope.from_box(Box([0, 0, 0], R, [0.5, 0.5, 0.5])).intersect(Polytope.plane([0, 0, 1], 0.1), Polytope.plane([1, 1, 0], 0.05)),
    ]
    for region in regions:
        slow = UniformSampler.from_simplices(simplices_of(reduce_affine(region)))
        fast = prepare_sampler(region)
        assert fast.dim == slow.dim
        assert fast.measure == pytest.approx(slow.measure, rel=1e-12)


def test_is_bounded_recession_rays():
    from prsc.geometry.triangulation import is_bounded

    eye = np.eye(3)
    assert is_bounded(np.vstack([eye, -eye]))
    assert not is_bounded(np.vstack([eye, -eye[:2]]))  # open along -z
    assert not is_bounded(np.array([[1.0, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0]]))  # a line (rank 2)
    assert not is_bounded(np.array([[1.0, 0, 0], [-1, 0, 0], [1, 0, 0], [-1, 0, 0]]))  # rank 1
    tetra = np.array([[1.0, 1, 1], [-1, -1, 1], [-1, 1, -1], [1, -1, -1]]) / np.sqrt(3)
    assert is_bounded(tetra)
    assert not is_bounded(tetra[:3])
    wedge = np.array([[0, 0, 1.0], [0.0, 0.6, -0.8], [0.0, -0.6, -0.8], [1, 0, 0]])  # open along -x
    assert not is_bounded(wedge)
    assert is_bounded(np.vstack([wedge, [-1, 0, 0]]))
    assert is_bounded(np.array([[1.0, 0], [-1, 0], [0, 1], [0, -1]]))
    assert not is_bounded(np.array([[1.0, 0], [-1, 0], [0, 1]]))
    assert is_bounded(np.array([[1.0], [-1.0]])) and not is_bounded(np.array([[1.0], [2.0]]))
