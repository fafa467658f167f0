"""Hit-and-run (the paper's Algorithm 1): stays inside, works on surfaces, converges."""

from __future__ import annotations

import numpy as np
from scipy.stats import ks_2samp

from prsc.geometry.boxes import Box
from prsc.geometry.hit_and_run import hit_and_run
from prsc.geometry.polytope import Polytope
from prsc.geometry.rotations import compat_euler_to_matrix
from prsc.geometry.uniform_sampling import prepare_sampler

R = compat_euler_to_matrix(0.4, 0.3, -0.2)


def test_converges_to_the_exact_law():
    region = Polytope.from_box(Box([0, 0, 0.5], R, [0.6, 0.3, 0.2])).intersect(Polytope.halfspace([1, 1, 1], 0.6))
    rng = np.random.default_rng(0)
    har = hit_and_run(region, rng, 4000, walk_length=100)
    exact = prepare_sampler(region).sample(rng, 4000)
    assert region.contains(har, tol=1e-9).all()
    for axis in range(3):  # loose: walks are only approximately independent and uniform
        assert ks_2samp(har[:, axis], exact[:, axis]).pvalue > 1e-4
    # Too short a walk from the centre is visibly not uniform (spread too small).
    short = hit_and_run(region, rng, 4000, walk_length=1)
    assert np.std(short[:, 0]) < 0.9 * np.std(exact[:, 0])


def test_works_on_a_surface_region():
    rect = Polytope.from_rectangle([0, 0, 1], R, 1.0, 0.5)
    rng = np.random.default_rng(1)
    x = hit_and_run(rect, rng, 2000, walk_length=50)
    local = (x - [0, 0, 1]) @ R
    assert np.max(np.abs(local[:, 2])) < 1e-9
    assert np.std(local[:, 0]) > 0.2  # it moves (uniform on [-0.5, 0.5]: std 0.289)
    assert ks_2samp(local[:, 0], rng.uniform(-0.5, 0.5, 2000)).pvalue > 1e-4


def test_single_chain_mode_and_point_region():
    box = Polytope.from_box(Box([0, 0, 0], np.eye(3), [1, 1, 1]))
    x = hit_and_run(box, np.random.default_rng(2), 50, walk_length=10, independent=False)
    assert x.shape == (50, 3) and box.contains(x).all()
    pt = Polytope.from_rows(np.zeros((0, 3)), [], C=np.eye(3), d=[1, 2, 3])
    assert np.allclose(hit_and_run(pt, np.random.default_rng(3), 3), [[1, 2, 3]] * 3)
