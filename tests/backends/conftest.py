"""Fixtures: the hand-made scenes compiled once into every format."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.backends.scenes import all_handmade

TARGETS = ["json", "mjcf", "urdf", "sdf", "usd"]


@pytest.fixture(scope="session")
def mesh_file(tmp_path_factory) -> Path:
    """A watertight mesh off-centre and out of scale, to be fitted to its object's box."""
    import trimesh

    mesh = trimesh.creation.cone(radius=3.0, height=5.0, sections=24)
    mesh.apply_translation([10.0, -4.0, 2.0])
    path = tmp_path_factory.mktemp("meshes") / "cone.obj"
    mesh.export(path)
    return path


@pytest.fixture(scope="session")
def handmade(tmp_path_factory, mesh_file) -> dict[str, tuple[dict, Path]]:
    """name -> (scene JSON, output folder of `prsc compile` with every target)."""
    from prsc.commands.compile import compile_scenes

    scenes = all_handmade(str(mesh_file))
    source = tmp_path_factory.mktemp("handmade_src")
    out = tmp_path_factory.mktemp("handmade_out")
    result = {}
    for name, scene in scenes.items():
        path = source / f"{name}.json"
        path.write_text(json.dumps(scene))
        # The mesh lives in a temporary folder, not beside the scenes' spec: allowed explicitly.
        root = compile_scenes(str(path), TARGETS, 1, 0, str(out), meshes_anywhere=True)
        result[name] = (scene, root)
    return result
