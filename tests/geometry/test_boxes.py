from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from prsc.geometry.boxes import Box, support
from prsc.geometry.rotations import compat_euler_to_matrix
from tests.geometry.strategies import half_extents, points, rotations

directions = st.tuples(*[st.floats(-1, 1) for _ in range(3)]).map(np.asarray)


@settings(max_examples=200, deadline=None)
@given(points, rotations, half_extents, st.lists(directions, min_size=1, max_size=5))
def test_support_is_max_over_corners(c, r, h, ns):
    box = Box(c, r, h)
    n = np.array(ns)
    s = box.support(n)
    brute = np.max((box.corners() - c) @ n.T, axis=0)
    assert np.allclose(s, brute, atol=1e-12)
    lo, hi = box.extent_along(n)
    assert np.allclose(hi, np.max(box.corners() @ n.T, axis=0), atol=1e-12)
    assert np.allclose(lo, np.min(box.corners() @ n.T, axis=0), atol=1e-12)


def test_support_vectorised_shape():
    r = compat_euler_to_matrix(0.1, 0.2, 0.3)
    n = np.random.default_rng(0).normal(size=(4, 7, 3))
    assert support(r, [1, 2, 3], n).shape == (4, 7)


@settings(max_examples=100, deadline=None)
@given(points, rotations, half_extents)
def test_aabb_is_tight_box_of_corners(c, r, h):
    box = Box(c, r, h)
    lo, hi = box.aabb()
    k = box.corners()
    assert np.allclose(lo, k.min(axis=0), atol=1e-12)
    assert np.allclose(hi, k.max(axis=0), atol=1e-12)
    assert box.contains(k, tol=1e-9).all()


def test_face_points_and_dimensions():
    r = compat_euler_to_matrix(0.5, 0.0, 0.0)
    box = Box.from_dimensions([1, 2, 3], r, [0.4, 0.6, 0.2])
    assert np.allclose(box.face_point([0, 0, 1]), [1, 2, 3.1])
    assert np.allclose(box.face_point([1, 0, 0]), np.array([1, 2, 3]) + 0.2 * r[:, 0])
    # back right = -y (back) and +x (right)
    assert np.allclose(box.face_point([1, -1, 0]), np.array([1, 2, 3]) + r @ [0.2, -0.3, 0])
    assert np.allclose(box.dimensions, [0.4, 0.6, 0.2])
    assert box.volume == np.prod([0.4, 0.6, 0.2])
    assert np.allclose(box.corners()[0], box.face_point([-1, -1, -1]))
