from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from prsc.geometry import rotations as rot
from tests.geometry.strategies import angles, rotations, unit_quats


@settings(max_examples=200, deadline=None)
@given(angles, angles, angles)
def test_compat_euler_is_scipy_zyx(a, b, c):
    expected = Rotation.from_euler("zyx", [a, b, c]).as_matrix()
    assert np.allclose(rot.compat_euler_to_matrix(a, b, c), expected, atol=1e-12)


def test_compat_euler_is_extrinsic_z_then_y_then_x():
    # Rx(c) Ry(b) Rz(a): a 90 deg yaw first turns +x into +y, then a 90 deg roll about world
    # x turns that +y into +z.
    m = rot.compat_euler_to_matrix(math.pi / 2, 0.0, math.pi / 2)
    assert np.allclose(m @ [1, 0, 0], [0, 0, 1], atol=1e-12)


@settings(max_examples=200, deadline=None)
@given(unit_quats)
def test_quaternion_matrix_round_trip_and_scipy(q):
    m = rot.quat_to_matrix(q)
    assert np.allclose(m, Rotation.from_quat(q, scalar_first=True).as_matrix(), atol=1e-12)
    back = rot.matrix_to_quat(m)
    assert back[0] >= 0
    assert np.allclose(back, q if q[0] >= 0 else -q, atol=1e-9) or abs(q[0]) < 1e-9
    assert rot.is_rotation(m)


def test_matrix_to_quat_batched_and_pivots():
    r = Rotation.from_quat(np.random.default_rng(3).normal(size=(500, 4))).as_matrix()
    # Include the w ~ 0 case (180 deg turns) where a naive formula divides by zero.
    r = np.concatenate([r, [rot.rot_x(math.pi), rot.rot_y(math.pi), rot.rot_z(math.pi)]])
    q = rot.matrix_to_quat(r)
    assert q.shape == (503, 4)
    assert np.allclose(rot.quat_to_matrix(q), r, atol=1e-12)


@settings(max_examples=200, deadline=None)
@given(rotations)
def test_rpy_matches_scipy_fixed_xyz_and_round_trips(m):
    rpy = rot.matrix_to_rpy(m)
    # 1e-8: near gimbal lock the yaw/roll split is only defined to about 1e-8.
    assert np.allclose(Rotation.from_euler("xyz", rpy).as_matrix(), m, atol=1e-8)
    assert np.allclose(rot.rpy_to_matrix(rpy), m, atol=1e-8)
    q = rot.matrix_to_quat(m)
    # Three conversions, each good to ~1e-8 at the gimbal-lock threshold (hypothesis found
    # 1.3e-8 at cos(pitch) = 1.3e-8).
    assert np.allclose(rot.quat_to_matrix(rot.rpy_to_quat(rot.quat_to_rpy(q))), m, atol=3e-8)


def test_rpy_gimbal_lock():
    m = rot.rpy_to_matrix([0.3, math.pi / 2, -0.2])
    assert np.allclose(rot.rpy_to_matrix(rot.matrix_to_rpy(m)), m, atol=1e-9)


@settings(max_examples=200, deadline=None)
@given(st.tuples(*[st.floats(-1, 1) for _ in range(3)]).filter(lambda v: np.linalg.norm(v) > 1e-3))
def test_rotation_taking_y_to(v):
    v = np.asarray(v)
    u = v / np.linalg.norm(v)
    m = rot.rotation_taking_y_to(v)
    assert rot.is_rotation(m)
    assert np.allclose(m @ [0, 1, 0], u, atol=1e-9)
    # Smallest rotation: its angle is the angle between +y and u.
    angle = Rotation.from_matrix(m).magnitude()
    assert angle == pytest.approx(math.acos(np.clip(u[1], -1, 1)), abs=1e-7)


def test_rotation_taking_y_to_special_cases():
    assert np.allclose(rot.rotation_taking_y_to([0, 2, 0]), np.eye(3))
    assert np.allclose(rot.rotation_taking_y_to([0, -1, 0]), rot.rot_z(math.pi), atol=1e-12)
    with pytest.raises(ValueError):
        rot.rotation_taking_y_to([0, 0, 0])


def test_yaw_toward():
    for target in ([1, 0, 5], [0, -3, 0], [-1, 1, 0]):
        theta = rot.yaw_toward(target)
        fwd = rot.yaw_matrix(theta) @ [0, 1, 0]
        horiz = np.array([target[0], target[1], 0.0])
        assert np.allclose(fwd, horiz / np.linalg.norm(horiz), atol=1e-12)
    with pytest.raises(ValueError):
        rot.yaw_toward([0, 0, 1])


def test_one_matrix_in_plain_floats_is_the_vectorised_quaternion():
    """scene_json's per-object quaternion (matrix_to_quat_one) has the bits of matrix_to_quat, pivots included."""
    from prsc.geometry.rotations import matrix_to_quat, matrix_to_quat_one, quat_to_matrix

    rng = np.random.default_rng(5)
    matrices = list(quat_to_matrix(rng.normal(size=(2000, 4)))) + [np.eye(3), np.diag([-1.0, -1.0, 1.0]), np.diag([1.0, -1.0, -1.0])]
    for m in matrices:
        assert matrix_to_quat_one(m.tolist()) == matrix_to_quat(m).tolist()
