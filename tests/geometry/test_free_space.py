"""Free-space decomposition: exact pieces, uniformity (chi-square, p > 0.001), dead ends."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chisquare

from prsc.geometry.boxes import Box
from prsc.geometry.exceptions import EmptyRegionError
from prsc.geometry.free_space import free_space, free_space_sampler
from prsc.geometry.obb import boxes_collide, collides_many, minkowski_obstacle
from prsc.geometry.polytope import Polytope
from prsc.geometry.rotations import rot_z

P_MIN = 1e-3
EYE = np.eye(3)


def _table_top(z: float, half_x: float, half_y: float) -> Polytope:
    """Centres on the plane z, |x| <= half_x, |y| <= half_y."""
    rows = np.array([[1.0, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0]])
    return Polytope.from_rows(rows, [half_x, half_x, half_y, half_y], C=[[0, 0, 1]], d=[z])


def test_square_with_a_centre_obstacle_is_uniform_2d():
    # Region [0,1]^2 on z = 1; a placed 0.4-wide cube at the centre and a new 0.1-wide
    # cube: the collision set is [0.25, 0.75]^2, exactly the 4 centre cells of a 4 x 4 grid.
    region = _table_top(1.0, 0.5, 0.5).translate([0.5, 0.5, 0.0])
    placed = Box([0.5, 0.5, 1.0], EYE, [0.2, 0.2, 0.2])
    obs = minkowski_obstacle(placed, EYE, [0.05, 0.05, 0.05], contact_tol=0.0)
    fs = free_space(region, [obs])
    assert fs.measure == pytest.approx(0.75, rel=1e-12)
    x = fs.sampler().sample(np.random.default_rng(0), 120_000)
    assert np.allclose(x[:, 2], 1.0)
    idx = np.minimum((x[:, :2] * 4).astype(int), 3)
    counts = np.zeros((4, 4))
    np.add.at(counts, (idx[:, 0], idx[:, 1]), 1)
    centre = np.zeros((4, 4), bool)
    centre[1:3, 1:3] = True
    assert counts[centre].sum() == 0
    assert chisquare(counts[~centre]).pvalue > P_MIN


def test_cube_with_a_centre_obstacle_is_uniform_3d():
    region = Polytope.from_box(Box([0.5, 0.5, 0.5], EYE, [0.5, 0.5, 0.5]))
    placed = Box([0.5, 0.5, 0.5], EYE, [0.2, 0.2, 0.2])
    obs = minkowski_obstacle(placed, EYE, [0.05, 0.05, 0.05], contact_tol=0.0)
    fs = free_space(region, [obs])
    assert fs.measure == pytest.approx(1 - 0.125, rel=1e-12)
    x = fs.sampler().sample(np.random.default_rng(1), 200_000)
    idx = np.minimum((x * 4).astype(int), 3)
    flat = np.ravel_multi_index(idx.T, (4, 4, 4))
    counts = np.bincount(flat, minlength=64).reshape(4, 4, 4)
    centre = np.zeros((4, 4, 4), bool)
    centre[1:3, 1:3, 1:3] = True
    assert counts[centre].sum() == 0
    assert chisquare(counts[~centre]).pvalue > P_MIN


def test_rotated_obstacles_measure_and_no_collisions():
    new_r, new_h = rot_z(0.5), np.array([0.05, 0.1, 0.1])
    placed = [Box([x, 0.0, 0.9], rot_z(a), [0.1, 0.15, 0.1]) for x, a in [(-0.5, 0.3), (0.0, 1.0), (0.45, -0.4)]]
    region = _table_top(0.9, 0.9, 0.4)
    region = Polytope.from_rows(region.A, region.b).erode_by_box(new_r, new_h).intersect(Polytope.plane([0, 0, 1], 0.9))
    fs = free_space(region, [minkowski_obstacle(b, new_r, new_h) for b in placed])
    s = fs.sampler()
    rng = np.random.default_rng(2)
    x = s.sample(rng, 20_000)
    assert region.contains(x, tol=1e-9).all()
    for b in placed:
        assert not collides_many(b, x, np.broadcast_to(new_r, (len(x), 3, 3)), np.broadcast_to(new_h, (len(x), 3))).any()
    # Free area against Monte Carlo over the region's rectangle.
    n = 200_000
    u = np.column_stack([rng.uniform(-0.9, 0.9, n), rng.uniform(-0.4, 0.4, n), np.full(n, 0.9)])
    free = region.contains(u, tol=0)
    for b in placed:
        free &= ~collides_many(b, u, np.broadcast_to(new_r, (n, 3, 3)), np.broadcast_to(new_h, (n, 3)))
    mc = free.mean() * 1.8 * 0.8
    assert fs.measure == pytest.approx(mc, abs=4 * np.sqrt(free.mean() * (1 - free.mean()) / n) * 1.44 + 1e-4)
    # The pieces are disjoint: the pieces' own measures add up to the sampler's.
    assert s.measure == pytest.approx(fs.measure, rel=1e-12)
    polys = fs.piece_polytopes()
    inside = np.sum([p.contains(x[:2000], tol=-1e-9) for p in polys], axis=0)
    assert inside.max() <= 1


def test_resting_on_an_object_is_free_and_full_cover_is_a_dead_end():
    table = Box([0, 0, 0.4], EYE, [0.5, 0.5, 0.4])
    cube_h = np.array([0.05, 0.05, 0.05])
    on_table = _table_top(0.85, 0.45, 0.45)
    # The table itself is an obstacle; resting on its top (z = 0.85) is contact, not collision.
    fs = free_space(on_table, [minkowski_obstacle(table, EYE, cube_h)])
    assert fs.measure == pytest.approx(0.81, rel=1e-12)
    p = fs.sampler().sample_one(np.random.default_rng(0))
    assert not boxes_collide(table, Box(p, EYE, cube_h))
    # A wide box filling the table top leaves nothing: a proof of a dead end.
    wide = Box([0, 0, 0.85], EYE, [0.6, 0.6, 0.05])
    dead = free_space(on_table, [minkowski_obstacle(wide, EYE, cube_h)])
    assert dead.is_empty and dead.measure == 0.0
    with pytest.raises(EmptyRegionError):
        free_space_sampler(on_table, [minkowski_obstacle(wide, EYE, cube_h)])


def test_many_obstacles_and_obstacles_off_the_plane():
    rng = np.random.default_rng(4)
    region = _table_top(1.0, 1.0, 1.0)
    boxes = [Box([*rng.uniform(-1, 1, 2), 1.0], rot_z(rng.uniform(0, 3)), [0.1, 0.1, 0.1]) for _ in range(8)]
    boxes.append(Box([0, 0, 3.0], EYE, [0.5, 0.5, 0.5]))  # far above: misses the plane
    obs = [minkowski_obstacle(b, EYE, [0.05, 0.05, 0.05]) for b in boxes]
    fs = free_space(region, obs)
    x = fs.sampler().sample(rng, 5000)
    for b in boxes:
        assert not collides_many(b, x, np.broadcast_to(EYE, (5000, 3, 3)), np.full((5000, 3), 0.05)).any()


def test_point_region():
    point = Polytope.from_rows(np.zeros((0, 3)), [], C=EYE, d=[0, 0, 0])
    near = minkowski_obstacle(Box([0.1, 0, 0], EYE, [0.1, 0.1, 0.1]), EYE, [0.05] * 3)
    far = minkowski_obstacle(Box([1, 0, 0], EYE, [0.1, 0.1, 0.1]), EYE, [0.05] * 3)
    assert free_space(point, [near]).is_empty
    assert np.allclose(free_space(point, [far]).sampler().sample_one(np.random.default_rng(0)), 0)
