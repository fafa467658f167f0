"""Mass properties of parts and of a body made of parts (uniform density, never identity)."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from prsc.assets.parts import Part
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


def _unit_second_moment(part: Part) -> tuple[float, np.ndarray, np.ndarray]:
    """Volume, centroid and second moment about the part origin (part frame, density 1)."""
    sx, sy, sz = part.size
    if part.shape == "box":
        v = sx * sy * sz
        return v, np.zeros(3), v / 12.0 * np.diag([sx * sx, sy * sy, sz * sz])
    if part.shape == "cylinder":
        r, h = part.radius, sz
        v = math.pi * r * r * h
        return v, np.zeros(3), v * np.diag([r * r / 4, r * r / 4, h * h / 12])
    if part.shape == "sphere":
        r = part.radius
        v = 4.0 / 3.0 * math.pi * r**3
        return v, np.zeros(3), v * r * r / 5 * np.eye(3)
    if part.shape == "mesh":
        props = mesh_properties(part.mesh)
        scale = np.diag(part.size)
        det = sx * sy * sz
        second = det * scale @ np.asarray(props.second_moment) @ scale
        return props.volume * det, scale @ np.asarray(props.centroid), second
    raise ValueError(f"unknown part shape {part.shape!r}")


@functools.lru_cache(maxsize=4096)
def composite_inertial(parts: tuple[Part, ...], mass: float) -> Inertial:
    """Mass properties of rigidly joined parts sharing `mass` in proportion to volume."""
    # Collision-only parts (convex pieces of a decomposed mesh) overlap the visible solid
    # they approximate: the mass lies in what is seen.
    solids = [part for part in parts if part.visible]
    if not solids:
        raise ValueError("a body needs at least one visible part")
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
