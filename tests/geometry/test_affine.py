from __future__ import annotations

import numpy as np
import pytest

from prsc.geometry.affine import reduce_affine
from prsc.geometry.boxes import Box
from prsc.geometry.exceptions import EmptyRegionError
from prsc.geometry.polytope import Polytope
from prsc.geometry.rotations import compat_euler_to_matrix

R = compat_euler_to_matrix(0.4, 0.3, -0.2)
BOX = Polytope.from_box(Box([0.1, 0.2, 0.3], R, [0.5, 0.4, 0.3]), label=0)


def test_full_dimensional_box():
    reg = reduce_affine(BOX)
    assert reg.dim == 3
    assert reg.radius == pytest.approx(0.3)
    # The ball fits: every row has slack >= radius at the centre (rows are unit).
    assert np.all(reg.b - reg.A @ reg.center >= reg.radius - 1e-12)


def test_explicit_equality_gives_a_plane():
    reg = reduce_affine(BOX.intersect(Polytope.plane(R[:, 2], R[:, 2] @ [0.1, 0.2, 0.3] + 0.1, label=1)))
    assert reg.dim == 2
    assert np.allclose(reg.basis.T @ reg.basis, np.eye(2))
    assert np.allclose(R[:, 2] @ reg.basis, 0, atol=1e-12)
    t = np.random.default_rng(0).normal(size=(10, 2))
    assert np.allclose(reg.project(reg.lift(t)), t)


def test_opposite_pair_is_an_equality():
    top = R[:, 2] @ [0.1, 0.2, 0.3] + 0.3  # the box's top face plane
    reg = reduce_affine(BOX.intersect(Polytope.halfspace(-R[:, 2], -top, label=1)))
    assert reg.dim == 2
    assert reg.radius == pytest.approx(0.4)


def test_implicit_equality_found_by_lp():
    # z <= 0, z >= x, z >= -x inside a box: only x = z = 0 remains (a segment along y);
    # no two rows are opposite, so only the LP can find it.
    box = Polytope.from_box(Box([0, 0, 0], np.eye(3), [1, 1, 1]))
    wedge = Polytope.from_rows([[0, 0, 1.0], [1, 0, -1.0], [-1, 0, -1.0]], [0, 0, 0], labels=[1, 2, 3])
    reg = reduce_affine(box.intersect(wedge))
    assert reg.dim == 1
    assert np.allclose(np.abs(reg.basis[:, 0]), [0, 1, 0], atol=1e-9)


def test_point_region():
    p = Polytope.from_rows(np.zeros((0, 3)), [], C=np.eye(3), d=[1, 2, 3])
    reg = reduce_affine(p.intersect(BOX.translate([0.9, 1.8, 2.7])))
    assert reg.dim == 0 and np.allclose(reg.origin, [1, 2, 3])


def test_empty_regions_raise_with_labels():
    far = Polytope.halfspace([1, 0, 0], -5.0, label=9)
    with pytest.raises(EmptyRegionError) as err:
        reduce_affine(BOX.intersect(far))
    assert 9 in err.value.labels
    with pytest.raises(EmptyRegionError):
        reduce_affine(Polytope.plane([0, 0, 1], 0.0).intersect(Polytope.plane([0, 0, 1], 1.0)))
    with pytest.raises(EmptyRegionError):
        reduce_affine(Polytope.halfspace([1, 0, 0], 0.0).intersect(Polytope.halfspace([-1, 0, 0], -1e-6)))


def test_nearly_touching_halfspaces_within_tolerance_are_a_plane():
    p = Polytope.halfspace([0, 0, 1], 0.5).intersect(Polytope.halfspace([0, 0, -1], -0.5 + 1e-13), BOX)
    assert reduce_affine(p).dim == 2
