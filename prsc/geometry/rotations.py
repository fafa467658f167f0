"""Rotations: matrices and unit quaternions (w, x, y, z), plus the two Euler conventions
prsc meets at its borders.

Internally prsc keeps rotation matrices (3x3, columns = the object's local axes in world
coordinates) or quaternions; Euler angles exist only at the edges:

* the *compat* spec form `Vector3D(a, b, c)`, which means scipy's
  `Rotation.from_euler('zyx', [a, b, c])`: extrinsic rotations about world z by a, then
  world y by b, then world x by c, i.e. the matrix Rx(c) @ Ry(b) @ Rz(a);
* URDF/SDF `rpy` (fixed axes x, then y, then z): the matrix Rz(yaw) @ Ry(pitch) @ Rx(roll).

Functions accept a single rotation or a stack (leading batch dimensions) where noted.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

# Below this |cos(pitch)| the roll/yaw split is numerically undefined (gimbal lock).
_GIMBAL_EPS = 1e-8


def rot_x(angle: float) -> NDArray[np.float64]:
    """Rotation matrix about the x axis by `angle` radians."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(angle: float) -> NDArray[np.float64]:
    """Rotation matrix about the y axis by `angle` radians."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(angle: float) -> NDArray[np.float64]:
    """Rotation matrix about the z axis by `angle` radians (a yaw)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


yaw_matrix = rot_z


def yaw_matrices(yaw: NDArray[np.float64]) -> NDArray[np.float64]:
    """`rot_z` of each yaw (n,): rotations (n, 3, 3)."""
    n = len(yaw)
    c, s = np.cos(yaw), np.sin(yaw)
    out = np.zeros((n, 3, 3))
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1], out[:, 2, 2] = c, -s, s, c, 1.0
    return out


def quat_to_matrix(q: ArrayLike) -> NDArray[np.float64]:
    """Unit quaternion(s) (..., 4) in w, x, y, z order to rotation matrices (..., 3, 3)."""
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    out = np.empty(q.shape[:-1] + (3, 3))
    out[..., 0, 0] = 1 - 2 * (y * y + z * z)
    out[..., 0, 1] = 2 * (x * y - w * z)
    out[..., 0, 2] = 2 * (x * z + w * y)
    out[..., 1, 0] = 2 * (x * y + w * z)
    out[..., 1, 1] = 1 - 2 * (x * x + z * z)
    out[..., 1, 2] = 2 * (y * z - w * x)
    out[..., 2, 0] = 2 * (x * z - w * y)
    out[..., 2, 1] = 2 * (y * z + w * x)
    out[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return out


def matrix_to_quat(m: ArrayLike) -> NDArray[np.float64]:
    """Rotation matrices (..., 3, 3) to unit quaternions (..., 4), w x y z with w >= 0."""
    m = np.asarray(m, dtype=float)
    batch = m.shape[:-2]
    r = m.reshape(-1, 3, 3)
    # Shepperd's method: pick the largest of 4w^2, 4x^2, 4y^2, 4z^2 as the pivot so the
    # division below is well conditioned for every rotation.
    diag = np.stack(
        [
            r[:, 0, 0] + r[:, 1, 1] + r[:, 2, 2],
            r[:, 0, 0] - r[:, 1, 1] - r[:, 2, 2],
            -r[:, 0, 0] + r[:, 1, 1] - r[:, 2, 2],
            -r[:, 0, 0] - r[:, 1, 1] + r[:, 2, 2],
        ],
        axis=1,
    )
    pivot = np.argmax(diag, axis=1)
    q = np.empty((r.shape[0], 4))
    s = np.sqrt(np.maximum(1.0 + diag[np.arange(r.shape[0]), pivot], 0.0)) * 2.0  # 4|q_pivot|
    d21 = r[:, 2, 1] - r[:, 1, 2]
    d02 = r[:, 0, 2] - r[:, 2, 0]
    d10 = r[:, 1, 0] - r[:, 0, 1]
    s01 = r[:, 0, 1] + r[:, 1, 0]
    s02 = r[:, 0, 2] + r[:, 2, 0]
    s12 = r[:, 1, 2] + r[:, 2, 1]
    cases = [
        np.stack([s / 4, d21 / s, d02 / s, d10 / s], axis=1),
        np.stack([d21 / s, s / 4, s01 / s, s02 / s], axis=1),
        np.stack([d02 / s, s01 / s, s / 4, s12 / s], axis=1),
        np.stack([d10 / s, s02 / s, s12 / s, s / 4], axis=1),
    ]
    with np.errstate(divide="ignore", invalid="ignore"):
        for k in range(4):
            sel = pivot == k
            q[sel] = cases[k][sel]
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q[q[:, 0] < 0] *= -1.0
    return q.reshape(batch + (4,))


def matrix_to_quat_one(r: list[list[float]]) -> list[float]:
    """`matrix_to_quat` of one matrix (rows as lists) in plain floats: the same pivots and bits; a numpy
    call per object cost more than the rest of a candidate scene's JSON."""
    diag = [r[0][0] + r[1][1] + r[2][2], r[0][0] - r[1][1] - r[2][2], -r[0][0] + r[1][1] - r[2][2], -r[0][0] - r[1][1] + r[2][2]]
    pivot = max(range(4), key=diag.__getitem__)
    s = math.sqrt(max(1.0 + diag[pivot], 0.0)) * 2.0
    d21, d02, d10 = r[2][1] - r[1][2], r[0][2] - r[2][0], r[1][0] - r[0][1]
    s01, s02, s12 = r[0][1] + r[1][0], r[0][2] + r[2][0], r[1][2] + r[2][1]
    q = ([s / 4, d21 / s, d02 / s, d10 / s], [d21 / s, s / 4, s01 / s, s02 / s],
         [d02 / s, s01 / s, s / 4, s12 / s], [d10 / s, s02 / s, s12 / s, s / 4])[pivot]
    norm = math.sqrt(sum(v * v for v in q))
    sign = -1.0 if q[0] / norm < 0 else 1.0
    return [sign * v / norm for v in q]


def compat_euler_to_matrix(a: float, b: float, c: float) -> NDArray[np.float64]:
    """The spec's compat `Vector3D(a, b, c)` orientation: Rx(c) @ Ry(b) @ Rz(a)."""
    return rot_x(c) @ rot_y(b) @ rot_z(a)


def rotation_taking_y_to(direction: ArrayLike) -> NDArray[np.float64]:
    """Smallest rotation taking local +y to unit(direction); 180 deg about z if antiparallel."""
    v = np.asarray(direction, dtype=float)
    norm = float(np.linalg.norm(v))
    if not norm > 0.0 or not math.isfinite(norm):
        raise ValueError(f"cannot face a zero or non-finite direction {v.tolist()}")
    v = v / norm
    y = np.array([0.0, 1.0, 0.0])
    cos = float(v[1])
    axis = np.cross(y, v)  # = (v_z, 0, -v_x)
    sin = float(np.linalg.norm(axis))
    if sin < 1e-12:
        return np.eye(3) if cos > 0 else rot_z(math.pi)
    k = axis / sin
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    # Rodrigues' formula.
    return np.eye(3) + sin * kx + (1.0 - cos) * (kx @ kx)


def yaw_toward(direction: ArrayLike) -> float:
    """Yaw angle about z that turns local +y toward the horizontal part of `direction`."""
    v = np.asarray(direction, dtype=float)
    if math.hypot(v[0], v[1]) == 0.0:
        raise ValueError(f"direction {v.tolist()} has no horizontal component")
    # rot_z(theta) @ (0, 1, 0) = (-sin theta, cos theta, 0)
    return math.atan2(-float(v[0]), float(v[1]))


def rpy_to_matrix(rpy: ArrayLike) -> NDArray[np.float64]:
    """URDF fixed-axis roll, pitch, yaw to the matrix Rz(yaw) @ Ry(pitch) @ Rx(roll)."""
    roll, pitch, yaw = (float(v) for v in np.asarray(rpy, dtype=float))
    return rot_z(yaw) @ rot_y(pitch) @ rot_x(roll)


def matrix_to_rpy(m: ArrayLike) -> NDArray[np.float64]:
    """Rotation matrix to URDF (roll, pitch, yaw); at gimbal lock roll is set to 0."""
    r = np.asarray(m, dtype=float)
    cp = math.hypot(r[0, 0], r[1, 0])  # |cos(pitch)|, accurate near gimbal lock
    pitch = math.atan2(-r[2, 0], cp)
    if cp < _GIMBAL_EPS:
        # cos(pitch) ~ 0: only yaw -/+ roll is defined; put it all in yaw. The error of
        # this split is of order cos(pitch), that of the general formula eps/cos(pitch):
        # the threshold balances the two at ~1e-8.
        roll = 0.0
        yaw = math.atan2(-r[0, 1], r[1, 1])
    else:
        roll = math.atan2(r[2, 1], r[2, 2])
        yaw = math.atan2(r[1, 0], r[0, 0])
    return np.array([roll, pitch, yaw])


def quat_to_rpy(q: ArrayLike) -> NDArray[np.float64]:
    """Quaternion (w, x, y, z) to URDF (roll, pitch, yaw)."""
    return matrix_to_rpy(quat_to_matrix(q))


def rpy_to_quat(rpy: ArrayLike) -> NDArray[np.float64]:
    """URDF (roll, pitch, yaw) to a quaternion (w, x, y, z), w >= 0."""
    return matrix_to_quat(rpy_to_matrix(rpy))


def is_rotation(m: ArrayLike, tol: float = 1e-9) -> bool:
    """True if `m` is a proper rotation matrix (orthonormal, determinant +1) within tol."""
    r = np.asarray(m, dtype=float)
    if r.shape != (3, 3) or not np.all(np.isfinite(r)):
        return False
    return bool(np.allclose(r.T @ r, np.eye(3), atol=tol) and abs(np.linalg.det(r) - 1) < tol)
