"""Mass properties of assets: formulas for primitives, trimesh as the independent check for
composite assets (tray, bowl) and fitted meshes; never an identity placeholder."""

from __future__ import annotations

import math

import numpy as np
import pytest

from prsc.assets.parts import Part
from prsc.assets.registry import PART_ASSETS
from prsc.backends.inertia import composite_inertial
from prsc.geometry.rotations import quat_to_matrix


def _trimesh_of(parts: tuple[Part, ...]):
    import trimesh

    meshes = []
    for part in parts:
        if part.shape == "box":
            mesh = trimesh.creation.box(extents=part.size)
        elif part.shape == "cylinder":
            mesh = trimesh.creation.cylinder(radius=part.radius, height=part.size[2], sections=256)
        elif part.shape == "sphere":
            mesh = trimesh.creation.icosphere(subdivisions=5, radius=part.radius)
        else:
            mesh = trimesh.load(part.mesh, force="mesh")
            mesh.apply_scale(part.size)
        transform = np.eye(4)
        transform[:3, :3] = quat_to_matrix(part.quaternion)
        transform[:3, 3] = part.position
        mesh.apply_transform(transform)
        meshes.append(mesh)
    return trimesh.util.concatenate(meshes)


def test_primitive_inertias_match_the_textbook():
    m = 2.0
    box = composite_inertial((Part("b", "box", (0.1, 0.2, 0.3)),), m)
    assert box.diagonal == pytest.approx((m * (0.04 + 0.09) / 12, m * (0.01 + 0.09) / 12, m * (0.01 + 0.04) / 12))
    cyl = composite_inertial((Part("c", "cylinder", (0.1, 0.1, 0.4)),), m)
    r, h = 0.05, 0.4
    assert cyl.diagonal == pytest.approx((m * (3 * r * r + h * h) / 12,) * 2 + (m * r * r / 2,))
    ball = composite_inertial((Part("s", "sphere", (0.2, 0.2, 0.2)),), m)
    assert ball.diagonal == pytest.approx((0.4 * m * 0.01,) * 3)
    for inertial in (box, cyl, ball):
        assert inertial.com == (0.0, 0.0, 0.0) and inertial.mass == m
        assert not np.allclose(inertial.diagonal, 1.0)


@pytest.mark.parametrize("model", sorted(PART_ASSETS))
def test_every_asset_matches_trimesh(model):
    dims = {"table": (1.8, 0.8, 0.8), "shelf": (0.8, 0.3, 1.2), "tray": (0.2364, 0.4522, 0.028964)}.get(model, (0.3, 0.25, 0.2))
    parts = PART_ASSETS[model](dims)
    mass = 3.0
    inertial = composite_inertial(parts, mass)
    mesh = _trimesh_of(parts)
    mesh.density = mass / mesh.volume
    assert np.allclose(inertial.com, mesh.center_mass, atol=1e-4 * max(dims))
    expected = np.asarray(mesh.moment_inertia)
    assert np.allclose(np.asarray(inertial.tensor), expected, rtol=2e-3, atol=1e-5 * np.abs(expected).max())
    # Principal moments and axes reproduce the tensor.
    axes = quat_to_matrix(inertial.principal)
    assert np.allclose(axes @ np.diag(inertial.diagonal) @ axes.T, np.asarray(inertial.tensor), atol=1e-12 + 1e-9 * expected.max())


def test_assets_stay_inside_their_box():
    for model, recipe in PART_ASSETS.items():
        dims = (0.3, 0.25, 0.2)
        mesh = _trimesh_of(recipe(dims))
        low, high = mesh.bounds
        assert np.all(low >= -np.asarray(dims) / 2 - 1e-9) and np.all(high <= np.asarray(dims) / 2 + 1e-9), model


def test_a_fitted_mesh_has_the_inertia_of_the_scaled_mesh(tmp_path):
    import trimesh

    from prsc.backends.store import AssetStore

    source = tmp_path / "cone.obj"
    cone = trimesh.creation.cone(radius=2.0, height=3.0, sections=64)
    cone.apply_translation([5.0, 1.0, -2.0])
    cone.export(source)
    unit = AssetStore(tmp_path / "store").normalised_mesh(source)
    part = Part("mesh", "mesh", (0.1, 0.3, 0.2), mesh=str(unit))
    inertial = composite_inertial((part,), 1.5)
    mesh = _trimesh_of((part,))
    mesh.density = 1.5 / mesh.volume
    assert np.allclose(mesh.bounds, [[-0.05, -0.15, -0.1], [0.05, 0.15, 0.1]], atol=1e-12)
    assert np.allclose(inertial.com, mesh.center_mass, atol=1e-9)
    assert np.allclose(np.asarray(inertial.tensor), mesh.moment_inertia, rtol=1e-6, atol=1e-12)
    assert math.isclose(inertial.mass, 1.5)
