"""Oriented-box collision: SAT against an exact LP check, contact tolerance, Minkowski obstacle."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings

from prsc.geometry.boxes import Box
from prsc.geometry.lp import chebyshev_center
from prsc.geometry.obb import boxes_collide, collides_many, minkowski_obstacle, penetration, projection_overlaps
from prsc.geometry.polytope import Polytope
from prsc.geometry.rotations import compat_euler_to_matrix, rot_x, rot_z
from tests.geometry.strategies import half_extents, points, rotations


def _lp_margin(a: Box, b: Box) -> float:
    """Radius of the largest ball inside both boxes (< 0: they are apart): exact, via LP."""
    p = Polytope.from_box(a).intersect(Polytope.from_box(b))
    return chebyshev_center(p.A, p.b)[1]


@settings(max_examples=300, deadline=None)
@given(points, rotations, half_extents, points, rotations, half_extents)
def test_sat_agrees_with_lp(ca, ra, ha, cb, rb, hb):
    a, b = Box(ca * 0.5, ra, ha), Box(cb * 0.5, rb, hb)
    pen = penetration(a, b)
    margin = _lp_margin(a, b)
    assume(abs(pen) > 1e-6 and abs(margin) > 1e-7)  # not a borderline touch
    assert (pen > 0) == (margin > 0)
    assert boxes_collide(a, b, contact_tol=0.0) == (margin > 0)


@settings(max_examples=100, deadline=None)
@given(points, rotations, half_extents, points, rotations, half_extents)
def test_sat_agrees_with_dense_points(ca, ra, ha, cb, rb, hb):
    # A point found in both boxes proves a collision; SAT must not miss it.
    a, b = Box(ca * 0.3, ra, ha), Box(cb * 0.3, rb, hb)
    rng = np.random.default_rng(0)
    local = rng.uniform(-1, 1, size=(4000, 3)) * ha
    x = a.center + local @ a.rotation.T
    if b.contains(x, tol=-1e-6).any():
        assert boxes_collide(a, b, contact_tol=0.0)


def test_parallel_edges_and_identical_rotations():
    r = compat_euler_to_matrix(0.3, 0.2, 0.1)
    a = Box([0, 0, 0], r, [0.5, 0.5, 0.5])
    assert boxes_collide(a, Box(r @ [0.9, 0, 0], r, [0.5, 0.5, 0.5]))
    assert not boxes_collide(a, Box(r @ [1.1, 0, 0], r, [0.5, 0.5, 0.5]))
    # Rotated about a shared axis only: 3 cross products vanish.
    b = Box(r @ [0, 0, 1.05], r @ rot_z(0.7), [0.5, 0.5, 0.5])
    assert not boxes_collide(a, b)


def test_resting_contact_is_not_a_collision():
    table = Box([0, 0, 0.4], rot_z(0.3), [0.9, 0.4, 0.4])
    cube = Box([0.1, 0.1, 0.8 + 0.05], rot_z(1.1), [0.05, 0.05, 0.05])
    assert penetration(table, cube) == pytest.approx(0.0, abs=1e-12)
    assert not boxes_collide(table, cube)
    sunk = Box([0.1, 0.1, 0.85 - 1e-9], rot_z(1.1), [0.05, 0.05, 0.05])
    assert not boxes_collide(table, sunk)  # rounding-level overlap: still contact
    deep = Box([0.1, 0.1, 0.85 - 1e-3], rot_z(1.1), [0.05, 0.05, 0.05])
    assert boxes_collide(table, deep)
    side = Box(table.center + table.rotation @ [0.95, 0, 0], table.rotation, [0.05, 0.05, 0.05])
    assert not boxes_collide(table, side)


def test_edge_edge_separation_needs_cross_axes():
    # Two long boxes crossing like an X, one above the other: all 6 face axes overlap,
    # only the cross product of the long edges separates them.
    a = Box([0, 0, 0], rot_x(np.pi / 4), [1, 0.1, 0.1])
    b_rot = rot_z(np.pi / 2) @ rot_x(np.pi / 4)
    n = np.cross(a.rotation[:, 0], b_rot[:, 0])
    n /= np.linalg.norm(n)
    sep = a.support(n) + Box([0, 0, 0], b_rot, [1, 0.1, 0.1]).support(n)
    apart = Box(1.01 * sep * n, b_rot, [1, 0.1, 0.1])
    ov = projection_overlaps(a.center, a.rotation, a.half_extents, apart.center, apart.rotation, apart.half_extents)
    assert np.all(ov[0, :6] > 0)  # no face axis separates
    assert _lp_margin(a, apart) < 0
    assert not boxes_collide(a, apart, contact_tol=0.0)
    close = Box(0.99 * sep * n, b_rot, [1, 0.1, 0.1])
    assert _lp_margin(close, a) > 0 and boxes_collide(a, close, contact_tol=0.0)


def test_collides_many_matches_pairwise():
    rng = np.random.default_rng(1)
    a = Box([0, 0, 0], compat_euler_to_matrix(0.3, 0.2, 0.1), [0.4, 0.3, 0.2])
    from scipy.spatial.transform import Rotation

    rots = Rotation.random(300, random_state=2).as_matrix()
    cs = rng.uniform(-1, 1, size=(300, 3))
    hs = rng.uniform(0.05, 0.4, size=(300, 3))
    many = collides_many(a, cs, rots, hs)
    pair = [boxes_collide(a, Box(c, r, h)) for c, r, h in zip(cs, rots, hs)]
    assert many.tolist() == pair
    assert 0 < many.sum() < 300


@settings(max_examples=100, deadline=None)
@given(points, rotations, half_extents, rotations, half_extents)
def test_minkowski_obstacle_is_the_collision_set(c, ra, ha, rb, hb):
    placed = Box(c, ra, ha)
    obs = minkowski_obstacle(placed, rb, hb, contact_tol=1e-6)
    rng = np.random.default_rng(3)
    lo, hi = placed.aabb()
    reach = np.abs(rb) @ hb
    p = rng.uniform(lo - reach, hi + reach, size=(300, 3))
    # Strict interior <=> collision (contact_tol is built into the rows).
    a = obs.A / np.linalg.norm(obs.A, axis=1, keepdims=True)
    b = obs.b / np.linalg.norm(obs.A, axis=1)
    depth = np.min(b - p @ a.T, axis=1)
    keep = np.abs(depth) > 1e-9
    coll = collides_many(placed, p, np.broadcast_to(rb, (300, 3, 3)), np.broadcast_to(hb, (300, 3)), 1e-6)
    assert np.array_equal((depth > 0)[keep], coll[keep])
    assert obs.A.shape[0] <= 30
