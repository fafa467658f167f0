"""The exact sampler is uniform on its feasible region: chi-square over cells at fixed
seeds (p > 0.001), end to end through small specs.

Expected cell probabilities come from the geometry written out here independently of the
sampler: closed forms for boxes and segments, and for the polygon and the region with
an obstacle a large Monte Carlo count of uniform points tested against the relations
themselves.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import chisquare

from prsc.ir import compile_program
from prsc.sampling import Sampler
from tests.sampling.scene_checks import euler_compat

P_MIN = 1e-3
N = 12_000


def _positions(tmp_path, text: str, name: str, n: int = N, seed: int = 11) -> tuple[np.ndarray, list]:
    spec = tmp_path / "spec.prs"
    spec.write_text(text)
    sampler = Sampler(compile_program(str(spec), ()), "exact")
    rows = []
    for index in range(n):
        result = sampler.sample(seed, index)
        assert result.stats.total == 0, result.stats.counts  # nothing rejected on these specs
        obj = next(o for o in result.objects if o.name == name)
        rows.append(obj.position)
    return np.array(rows), result.objects


def _chi2(cells: np.ndarray, probs: np.ndarray, bins: int) -> float:
    observed = np.bincount(cells, minlength=bins)[:bins]
    probs = probs / probs.sum()
    keep = probs > 0
    assert observed[~keep].sum() == 0, "samples in cells of probability 0"
    return float(chisquare(observed[keep], probs[keep] * observed.sum()).pvalue)


def test_uniform_in_a_rotated_region_eroded_by_a_rotated_box(tmp_path):
    text = (
        "from tabletop import *\n"
        "c = Cube with width 0.1, with length 0.06, with height 0.08, facing 0.7,\n"
        "    completely in Cuboid(Vector3D(0.2, -0.1, 1.0), Vector3D(0.5, 0.3, 0.2), 0.6, 0.5, 0.4)\n"
    )
    pts, objects = _positions(tmp_path, text, "c")
    region_r = euler_compat(0.5, 0.3, 0.2)
    cube_r = objects[0].rotation
    half_cube = np.array([0.05, 0.03, 0.04])
    # In the region's frame the eroded region is a box: half extents minus the support.
    half = np.array([0.3, 0.25, 0.2]) - np.abs(region_r.T @ cube_r) @ half_cube
    local = (pts - np.array([0.2, -0.1, 1.0])) @ region_r
    assert np.all(np.abs(local) <= half + 1e-9)
    k = 4
    idx = np.clip(((local + half) / (2 * half) * k).astype(int), 0, k - 1)
    cells = idx[:, 0] * k * k + idx[:, 1] * k + idx[:, 2]
    assert _chi2(cells, np.ones(k**3), k**3) > P_MIN


def test_uniform_on_a_polygon_on_a_tilted_table_top(tmp_path):
    text = (
        "from tabletop import *\n"
        "t = Table at Vector3D(0, 0, 1.0), with width 1.0, with length 0.6, with height 0.1,\n"
        "    with orientation Vector3D(0.5, 0.15, -0.1)\n"
        "c = Cube completely on t, left of Vector3D(0.15, 0, 0)\n"
    )
    pts, objects = _positions(tmp_path, text, "c")
    table = objects[0]
    r = table.rotation
    top = table.position + r[:, 2] * 0.05
    half_cube = np.full(3, 0.02)
    s = lambda n: float(np.abs(n @ np.eye(3)) @ half_cube)  # the cube is not rotated
    u, v, n = r[:, 0], r[:, 1], r[:, 2]
    local = np.stack([(pts - top) @ u, (pts - top) @ v], axis=1)
    assert np.allclose((pts - top) @ n, s(n), atol=1e-9)
    # Monte Carlo reference: uniform points of the top rectangle, kept where the relations hold.
    rng = np.random.default_rng(2024)
    m = 2_000_000
    au, av = 0.5 - s(u), 0.3 - s(v)
    ref = np.stack([rng.uniform(-au, au, m), rng.uniform(-av, av, m)], axis=1)
    world = top + ref[:, :1] * u + ref[:, 1:] * v + s(n) * n
    ref = ref[world[:, 0] <= 0.15 - 0.02]
    assert local[:, 0].max() <= au + 1e-9 and np.all(pts[:, 0] <= 0.13 + 1e-9)
    k = 6
    edges_u = np.linspace(-au, au, k + 1)
    edges_v = np.linspace(-av, av, k + 1)

    def cell(a):
        i = np.clip(np.searchsorted(edges_u, a[:, 0]) - 1, 0, k - 1)
        j = np.clip(np.searchsorted(edges_v, a[:, 1]) - 1, 0, k - 1)
        return i * k + j

    probs = np.bincount(cell(ref), minlength=k * k).astype(float)
    assert _chi2(cell(local), probs, k * k) > P_MIN


def test_uniform_on_the_segment_of_aligned_with(tmp_path):
    text = (
        "from tabletop import *\n"
        "t = Table at Vector3D(0, 0, 0.4), with width 1.2, with length 0.8, with height 0.8, facing 0.3\n"
        "c = Cube on t, aligned with Vector3D(0.25, 0, 0) on x\n"
    )
    pts, objects = _positions(tmp_path, text, "c")
    assert np.allclose(pts[:, 0], 0.25, atol=1e-12) and np.allclose(pts[:, 2], 0.82, atol=1e-9)
    # The line x = 0.25 across the yawed top rectangle |u.q| <= 0.6, |v.q| <= 0.4 (q = p - centre).
    yaw = 0.3
    u = np.array([np.cos(yaw), np.sin(yaw)])
    v = np.array([-np.sin(yaw), np.cos(yaw)])
    lo, hi = -np.inf, np.inf
    for axis, half in ((u, 0.6), (v, 0.4)):
        # |axis . (0.25, y)| <= half, linear in y
        a, b = axis[1], axis[0] * 0.25
        ends = sorted(((half - b) / a, (-half - b) / a))
        lo, hi = max(lo, ends[0]), min(hi, ends[1])
    y = pts[:, 1]
    assert y.min() >= lo - 1e-9 and y.max() <= hi + 1e-9
    k = 20
    cells = np.clip(((y - lo) / (hi - lo) * k).astype(int), 0, k - 1)
    assert _chi2(cells, np.ones(k), k) > P_MIN


def test_uniform_on_a_table_minus_an_obstacle(tmp_path):
    text = (
        "from tabletop import *\n"
        "t = Table at Vector3D(0, 0, 0.4), with width 1.0, with length 0.6, with height 0.8\n"
        "o = Box at Vector3D(0.1, 0.05, 0.95)\n"
        "c = ToyCube with width 0.2, with length 0.1, with height 0.1, completely on t\n"
    )
    pts, _ = _positions(tmp_path, text, "c")
    # Free: the centre rectangle |x| <= 0.4, |y| <= 0.25 minus the obstacle's Minkowski box
    # |x - 0.1| < 0.15 + 0.1, |y - 0.05| < 0.15 + 0.05.
    blocked = (np.abs(pts[:, 0] - 0.1) < 0.25 - 1e-9) & (np.abs(pts[:, 1] - 0.05) < 0.2 - 1e-9)
    assert not blocked.any()
    rng = np.random.default_rng(7)
    m = 2_000_000
    ref = np.stack([rng.uniform(-0.4, 0.4, m), rng.uniform(-0.25, 0.25, m)], axis=1)
    ref = ref[~((np.abs(ref[:, 0] - 0.1) < 0.25) & (np.abs(ref[:, 1] - 0.05) < 0.2))]
    k = 8

    def cell(a):
        i = np.clip(((a[:, 0] + 0.4) / 0.8 * k).astype(int), 0, k - 1)
        j = np.clip(((a[:, 1] + 0.25) / 0.5 * k).astype(int), 0, k - 1)
        return i * k + j

    probs = np.bincount(cell(ref), minlength=k * k).astype(float)
    assert _chi2(cell(pts[:, :2]), probs, k * k) > P_MIN
