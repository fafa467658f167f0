from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings

from prsc.geometry.boxes import CORNER_SIGNS, Box
from prsc.geometry.polytope import NO_LABEL, Polytope, intersect
from prsc.geometry.rotations import compat_euler_to_matrix, rot_z
from tests.geometry.strategies import half_extents, points, rotations


def test_box_polytope_matches_box_contains():
    box = Box([0.3, -0.2, 0.5], compat_euler_to_matrix(0.4, 0.3, -0.2), [0.5, 0.2, 0.3])
    p = Polytope.from_box(box, label=7)
    x = np.random.default_rng(0).uniform(-1, 1.5, size=(5000, 3))
    assert np.array_equal(p.contains(x, tol=0), box.contains(x, tol=0))
    assert set(p.labels.tolist()) == {7}


def test_intersection_stacks_rows_and_labels():
    a = Polytope.halfspace([1, 0, 0], 1.0, label=1)
    b = Polytope.plane([0, 0, 1], 0.5, label=2)
    c = intersect(a, b, Polytope.everything())
    assert c.A.shape == (1, 3) and c.C.shape == (1, 3)
    assert c.labels.tolist() == [1] and c.eq_labels.tolist() == [2]
    assert c.contains([[0, 0, 0.5]]).all() and not c.contains([[2, 0, 0.5]]).any()
    with pytest.raises(ValueError):
        intersect(a, Polytope.everything(2))


def test_rectangle_polytope():
    r = compat_euler_to_matrix(0.2, 0.5, 0.1)
    rect = Polytope.from_rectangle([1, 1, 1], r, 2.0, 1.0, label=3)
    inside = np.array([1, 1, 1]) + r @ [0.9, -0.4, 0]
    off_plane = inside + 1e-3 * r[:, 2]
    assert rect.contains([inside]).all() and not rect.contains([off_plane]).any()


@settings(max_examples=150, deadline=None)
@given(points, rotations, half_extents, rotations, half_extents, points)
def test_erosion_keeps_every_corner_inside_and_is_tight(c, r, h, r_obj, h_obj, cut):
    # A rotated box cut by a random half-space through a point near its centre.
    normal = cut if np.linalg.norm(cut) > 1e-3 else np.array([1.0, 0, 0])
    region = Polytope.from_box(Box(c, r, h + 0.5)).intersect(Polytope.halfspace(normal, normal @ (c + 0.1 * cut)))
    eroded = region.erode_by_box(r_obj, h_obj * 0.5)
    hh = h_obj * 0.5
    rng = np.random.default_rng(0)
    # Points of the eroded set: random points in the region's bounding box kept by contains.
    lo, hi = Box(c, r, h + 0.5).aabb()
    x = rng.uniform(lo, hi, size=(2000, 3))
    x = x[eroded.contains(x, tol=0)]
    corners = x[:, None, :] + (CORNER_SIGNS * hh) @ r_obj.T  # (n, 8, 3)
    assert region.contains(corners.reshape(-1, 3), tol=1e-9).all()
    # Tightness: on each eroded row's boundary a corner touches the original face.
    for i in range(len(eroded.b)):
        a = eroded.A[i]
        worst = np.max((CORNER_SIGNS * hh) @ r_obj.T @ a)
        assert worst + eroded.b[i] == pytest.approx(region.b[i], abs=1e-12)


def test_erosion_of_an_equality_by_a_thick_box_is_empty_but_labelled():
    plane = Polytope.plane([0, 0, 1], 0.5, label=4)
    thick = plane.erode_by_box(np.eye(3), [0.1, 0.1, 0.1])
    assert thick.C.shape[0] == 0 and thick.A.shape[0] == 2 and thick.labels.tolist() == [4, 4]
    assert not thick.contains([[0, 0, 0.5]]).any()
    flat = plane.erode_by_box(np.eye(3), [0.1, 0.1, 0.0])  # flat along the normal: kept
    assert flat.C.shape[0] == 1


def test_translate_normalize_and_labels():
    p = Polytope.from_rows([[2.0, 0, 0]], [2.0], labels=None)
    assert p.labels.tolist() == [NO_LABEL]
    n = p.normalized()
    assert np.allclose(n.A, [[1, 0, 0]]) and np.allclose(n.b, [1.0])
    t = p.translate([1, 0, 0])
    assert t.contains([[2, 0, 0]]).all() and not t.contains([[2.1, 0, 0]]).any()
    assert p.with_label(5).labels.tolist() == [5]
    with pytest.raises(ValueError):
        Polytope.from_rows([[1.0, 0, 0]], [np.nan])


def test_erosion_of_rotated_box_by_yawed_box():
    # A 2 x 1 slab eroded by a 0.2 x 0.4 box turned 90 deg: the footprint swaps axes.
    region = Polytope.from_box(Box([0, 0, 0], np.eye(3), [1.0, 0.5, 0.5]))
    e = region.erode_by_box(rot_z(np.pi / 2), [0.1, 0.2, 0.1])
    assert np.allclose(np.sort(e.b), np.sort([0.8, 0.8, 0.4, 0.4, 0.4, 0.4]), atol=1e-12)
