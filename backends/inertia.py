"""Mass properties of parts and of a body made of parts (uniform density, never identity)."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from prsc.assets.parts import IDENTITY, Part
from prsc.geometry.rotations import matrix_to_quat, quat_to_matrix


@dataclass(frozen=True)
class Inertial:
    """A body's mass, centre of mass and inertia tensor about it, in the body frame."""

    mass: float
    com: tuple[float, float, float]
    tensor: tuple[tuple[float, float, float], ...]  # 3x3, symmetric, about the com
    diagonal: tuple[float, float, float]  # principal moments
    principal: tuple[float, float, float, float]  # w x y z: principal axes in the body frame


@dataclass(frozen=True)
class MeshProperties:
    """Volume, centroid and second moment (density 1, about the origin) of a unit mesh."""

    volume: float
    centroid: tuple[float, float, float]
    second_moment: tuple[tuple[float, float, float], ...]  # integral of r r^T dV


@functools.lru_cache(maxsize=64)
def mesh_properties(path: str) -> MeshProperties:
    """Mass properties of a normalised mesh file; its convex hull when it is not a solid."""
    import trimesh

    from prsc.user_assets.mesh_paths import read_trimesh

    loaded = read_trimesh(path, force="mesh")
    # Geometry only: a textured mesh repeats vertices along its UV seams, merged here into one solid.
    mesh = trimesh.Trimesh(loaded.vertices, loaded.faces)
    if not mesh.is_volume:
        mesh = mesh.convex_hull
    volume = float(mesh.volume)
    centroid = np.asarray(mesh.center_mass, dtype=float)
    inertia_com = np.asarray(mesh.moment_inertia, dtype=float) * (1.0 / mesh.density)
    cov_com = np.trace(inertia_com) / 2 * np.eye(3) - inertia_com
    second = cov_com + volume * np.outer(centroid, centroid)
    return MeshProperties(volume, tuple(centroid), tuple(map(tuple, second)))


PRIMITIVES = ("box", "cylinder", "sphere")
"""Part shapes whose mass properties are formulas of their size."""


def primitive_moments(shape: str, sx: Any, sy: Any, sz: Any) -> tuple[Any, tuple[Any, Any, Any]]:
    """Volume and principal second moments (density 1, about the centre) of a box, z-axis cylinder
    or sphere of full extents sx, sy, sz: floats, or arrays of many at once (the same numbers)."""
    if shape == "box":
        v = sx * sy * sz
        return v, (v / 12.0 * (sx * sx), v / 12.0 * (sy * sy), v / 12.0 * (sz * sz))
    if shape == "cylinder":
        r = np.minimum(sx, sy) / 2  # Part.radius
        v = math.pi * r * r * sz
        return v, (v * (r * r / 4), v * (r * r / 4), v * (sz * sz / 12))
    if shape == "sphere":
        r = np.minimum(np.minimum(sx, sy), sz) / 2
        v = 4.0 / 3.0 * math.pi * (r * r * r)  # not r**3: numpy's vectorised pow rounds otherwise than C's
        moment = v * r * r / 5
        return v, (moment, moment, moment)
    raise ValueError(f"not a primitive part shape: {shape!r}")


def primitive_inertia(shape: str, sizes: np.ndarray, masses: np.ndarray) -> np.ndarray:
    """Principal moments (rows x y z) of bodies each one primitive part of full extents `sizes`
    (rows) at the body's origin, of `masses`: the axes are the body's, the centre of mass its origin."""
    volume, moments = primitive_moments(shape, *np.asarray(sizes, dtype=float).T)
    density = np.asarray(masses, dtype=float) / volume
    s0, s1, s2 = (density * m for m in moments)
    trace = s0 + s1 + s2  # as composite_inertial's tensor: trace(second) I - second
    inertia = np.empty(np.shape(trace) + (3,))
    inertia[..., 0], inertia[..., 1], inertia[..., 2] = trace - s0, trace - s1, trace - s2
    return inertia


def _unit_second_moment(part: Part) -> tuple[float, np.ndarray, np.ndarray]:
    """Volume, centroid and second moment about the part origin (part frame, density 1)."""
    sx, sy, sz = part.size
    if part.shape in PRIMITIVES:
        v, moments = primitive_moments(part.shape, sx, sy, sz)
        return float(v), np.zeros(3), np.diag(moments)
    if part.shape == "mesh":
        props = mesh_properties(part.mesh)
        scale = np.diag(part.size)
        det = sx * sy * sz
        second = det * scale @ np.asarray(props.second_moment) @ scale
        return props.volume * det, scale @ np.asarray(props.centroid), second
    raise ValueError(f"unknown part shape {part.shape!r}")


def is_plain_primitive(part: Part) -> bool:
    """A box, cylinder or sphere at the body's origin, along its axes."""
    return part.shape in PRIMITIVES and part.position == (0.0, 0.0, 0.0) and part.quaternion == IDENTITY


@functools.lru_cache(maxsize=4096)
def composite_inertial(parts: tuple[Part, ...], mass: float) -> Inertial:
    """Mass properties of rigidly joined parts sharing `mass` in proportion to volume."""
    # Collision-only parts (convex pieces of a decomposed mesh) overlap the visible solid
    # they approximate: the mass lies in what is seen.
    solids = [part for part in parts if part.visible]
    if not solids:
        raise ValueError("a body needs at least one visible part")
    if len(solids) == 1 and is_plain_primitive(solids[0]):
        # One primitive at the origin: the formula shared with a shared model's resets (prsc.backends.shared_model).
        return _with_principal_axes(mass, np.zeros(3), np.diag(primitive_inertia(
            solids[0].shape, np.array([solids[0].size]), np.array([mass]))[0]))
    volumes, centroids, seconds = [], [], []
    for part in solids:
        v, c, s = _unit_second_moment(part)
        rot = quat_to_matrix(part.quaternion)
        pos = np.asarray(part.position, dtype=float)
        # Move the part's moments into the body frame: rotate, then shift by its position.
        c_body = rot @ c + pos
        s_body = rot @ s @ rot.T + np.outer(rot @ c, pos) * v + np.outer(pos, rot @ c) * v + v * np.outer(pos, pos)
        volumes.append(v)
        centroids.append(c_body)
        seconds.append(s_body)
    total = float(sum(volumes))
    density = mass / total
    com = sum(v * c for v, c in zip(volumes, centroids)) / total
    second = density * sum(seconds) - mass * np.outer(com, com)  # about the com
    tensor = np.trace(second) * np.eye(3) - second
    tensor = (tensor + tensor.T) / 2
    return _with_principal_axes(mass, com, tensor)


def _with_principal_axes(mass: float, com: np.ndarray, tensor: np.ndarray) -> Inertial:
    """Attach principal moments and axes; a diagonal tensor keeps the body axes."""
    off = abs(tensor[0, 1]) + abs(tensor[0, 2]) + abs(tensor[1, 2])
    if off <= 1e-12 * max(np.trace(tensor), 1e-300):
        diagonal = np.diag(tensor).copy()
        quat = np.array([1.0, 0.0, 0.0, 0.0])
    else:
        diagonal, axes = np.linalg.eigh(tensor)
        if np.linalg.det(axes) < 0:
            axes[:, 2] *= -1.0
        quat = matrix_to_quat(axes)
    com = np.where(np.abs(com) < 1e-15, 0.0, com)  # no -0.0 or 1e-18 noise in files
    return Inertial(
        mass=float(mass),
        com=tuple(float(v) for v in com),
        tensor=tuple(tuple(float(v) for v in row) for row in tensor),
        diagonal=tuple(float(v) for v in diagonal),
        principal=tuple(float(v) for v in quat),
    )
