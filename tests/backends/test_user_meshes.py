"""Meshes as users bring them: sizes from the mesh bounds times `scale`, convex decomposition
written as collision pieces in every format, a missing mesh caught by `prsc check`, USD
scenes with meshes that open without pxr warnings, and the example spec specs/user_mesh.prs."""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from tests.backends import readback
from tests.backends.scenes import obj, scene
from tests.backends.specs import REPO

TARGETS = ["json", "mjcf", "urdf", "sdf", "usd"]
TROUGH_FLOOR = 0.02  # the U's inner floor, metres above its bottom
CUBE = 0.03


def _u_mesh(path: Path) -> Path:
    """A U-shaped solid opening upwards: 0.1 m along x, 0.05 m along y, 0.06 m high."""
    import trimesh
    from shapely.geometry import Polygon

    outline = Polygon([(0, 0), (0.1, 0), (0.1, 0.06), (0.08, 0.06), (0.08, TROUGH_FLOOR),
                       (0.02, TROUGH_FLOOR), (0.02, 0.06), (0, 0.06)])
    mesh = trimesh.creation.extrude_polygon(outline, 0.05)  # outline in x-y, extruded along z
    mesh.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))  # y up -> z up
    mesh.export(path)
    return path


@pytest.fixture(scope="module")
def build_dir(tmp_path_factory):
    """A fresh decomposition cache for the U tests (PRSC_BUILD_DIR while they compile)."""
    return tmp_path_factory.mktemp("build")


def _cup_scene(folder: Path, collision: str) -> Path:
    """A static U (decomposed or hull) with a free cube resting on the floor of its trough."""
    _u_mesh(folder / "u.obj")
    u = obj("u", "U", (0.0, 0.0, 0.03), (0.1, 0.05, 0.06), static=True, shape="mesh",
            properties={"mesh": "u.obj", "collision": collision})
    cube = obj("cube", "Cube", (0.0, 0.0, TROUGH_FLOOR + CUBE / 2), (CUBE, CUBE, CUBE), color=(1, 0, 0, 1))
    path = folder / f"u_{collision}.json"
    path.write_text(json.dumps(scene([u, cube], spec=str(folder / "u.prs"))))
    return path


@pytest.fixture(scope="module")
def compiled(build_dir, tmp_path_factory):
    """collision -> output folder of the U scene compiled to every format."""
    from prsc.commands.compile import compile_scenes

    folder = tmp_path_factory.mktemp("u")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("PRSC_BUILD_DIR", str(build_dir))
        return {c: compile_scenes(str(_cup_scene(folder, c)), TARGETS, 1, 0, str(folder / "out"))
                for c in ("decomposed", "hull")}


def _pieces(root: Path) -> list[Path]:
    return sorted((root / "assets" / "meshes" / "convex").glob("*/*.obj"))


def test_a_concave_mesh_decomposes_into_several_convex_pieces_cached_in_the_build_folder(compiled, build_dir, monkeypatch):
    import trimesh

    from prsc.assets.convex_pieces import convex_pieces

    pieces = _pieces(compiled["decomposed"])
    assert len(pieces) >= 3, f"a U needs a floor and two walls, got {len(pieces)} pieces"
    for piece in pieces:
        assert trimesh.load(piece, force="mesh").is_convex, piece.name
    # A second use reads the cache: CoACD is not run again.
    import coacd

    monkeypatch.setattr(coacd, "run_coacd", lambda *a, **k: pytest.fail("decomposed twice"))
    monkeypatch.setenv("PRSC_BUILD_DIR", str(build_dir))
    source = next((compiled["decomposed"] / "assets" / "meshes").glob("u-*.obj"))
    cached = convex_pieces(source)
    assert [p.read_bytes() for p in cached] == [p.read_bytes() for p in pieces]
    assert cached[0].is_relative_to(build_dir)


def _settle(model_path: Path, seconds: float = 1.0) -> float:
    """How far the cube moved (m) in `seconds` of MuJoCo simulation."""
    import mujoco

    model = mujoco.MjModel.from_xml_path(str(model_path))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    body = model.body("cube").id
    start = data.xpos[body].copy()
    while data.time < seconds:
        mujoco.mj_step(model, data)
    return float(np.linalg.norm(data.xpos[body] - start))


def test_mujoco_collides_the_pieces_so_an_object_rests_inside_the_concavity(compiled):
    import mujoco

    path = compiled["decomposed"] / "mjcf" / "00000.xml"
    model = mujoco.MjModel.from_xml_path(str(path))
    colliding = [g for g in range(model.ngeom) if model.geom_bodyid[g] == model.body("u").id and model.geom_contype[g]]
    assert len(colliding) == len(_pieces(compiled["decomposed"]))
    assert all(model.geom_group[g] == 3 for g in colliding), "collision pieces are hidden from renders"
    assert _settle(path) < 0.002
    # The same scene with the hull: the cube starts inside the hull and is thrown out.
    assert _settle(compiled["hull"] / "mjcf" / "00000.xml") > 0.01


def test_pybullet_loads_the_pieces_from_the_urdf_and_the_sdf(compiled):
    import pybullet

    root = compiled["decomposed"]
    count = len(_pieces(root))
    urdf = root / "urdf" / "00000" / "u.urdf"
    assert len(ET.parse(urdf).getroot().findall("link/collision")) == count
    assert len(ET.parse(urdf).getroot().findall("link/visual")) == 1
    readback.urdf_validate(urdf.parent)
    client = pybullet.connect(pybullet.DIRECT)
    try:
        body = pybullet.loadURDF(str(urdf), physicsClientId=client)
        assert len(pybullet.getCollisionShapeData(body, -1, physicsClientId=client)) == count
        bodies = pybullet.loadSDF(str(root / "sdf" / "00000.sdf"), physicsClientId=client)
        names = {pybullet.getBodyInfo(b, physicsClientId=client)[1].decode(): b for b in bodies}
        assert len(pybullet.getCollisionShapeData(names["u"], -1, physicsClientId=client)) == count
    finally:
        pybullet.disconnect(client)


@pytest.mark.skipif(importlib.util.find_spec("pydrake") is None, reason="pydrake (dev extras) not installed")
def test_drake_registers_every_piece_as_a_collision_geometry(compiled):
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
    from pydrake.systems.framework import DiagramBuilder

    root = compiled["decomposed"]
    for path in (root / "sdf" / "00000.sdf", root / "mjcf" / "00000.xml"):
        plant, _ = AddMultibodyPlantSceneGraph(DiagramBuilder(), 0.0)
        Parser(plant).AddModels(str(path))
        plant.Finalize()
        u = next(plant.GetBodyByName("u", m) for m in map(plant.GetModelInstanceByName, ["u"])
                 if plant.HasBodyNamed("u", m)) if path.suffix == ".sdf" else plant.GetBodyByName("u")
        assert len(plant.GetCollisionGeometriesForBody(u)) == len(_pieces(root)), path.name


_USD_PROBE = """
import sys
from pxr import Usd, UsdGeom, UsdPhysics
stage = Usd.Stage.Open(sys.argv[1])
meshes = [UsdGeom.Mesh(p) for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
print(len(meshes), sum(len(m.GetPointsAttr().Get() or []) > 0 for m in meshes),
      sum(p.HasAPI(UsdPhysics.CollisionAPI) for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)),
      sum(UsdGeom.Imageable(p).ComputePurpose() == "guide" for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)))
"""


def test_usd_scenes_with_meshes_compile_and_open_without_pxr_warnings(compiled, build_dir, tmp_path):
    # Compiling in a fresh process: pxr writes its warnings to the C stderr.
    spec = tmp_path / "u.prs"
    _u_mesh(tmp_path / "u.obj")
    spec.write_text('u = Object at Vector3D(0, 0, 0.03), with mesh "u.obj", with collision "decomposed"\n'
                    'v = Object at Vector3D(0.3, 0, 0.03), with mesh "u.obj"\n')
    env = dict(os.environ, PRSC_BUILD_DIR=str(build_dir))
    run = subprocess.run([sys.executable, "-m", "prsc.cli", "compile", str(spec), "--target", "usd", "-n", "1",
                          "-o", str(tmp_path / "out")], capture_output=True, text=True, env=env, timeout=300)
    assert run.returncode == 0, run.stderr
    assert "Warning" not in run.stderr and "Could not open asset" not in run.stderr, run.stderr
    path = tmp_path / "out" / "u" / "usd" / "00000.usda"
    probe = subprocess.run([sys.executable, "-c", _USD_PROBE, str(path)], capture_output=True, text=True, timeout=120)
    assert probe.returncode == 0 and probe.stderr == "", probe.stderr
    meshes, resolved, colliders, guides = map(int, probe.stdout.split())
    pieces = len(_pieces(tmp_path / "out" / "u"))
    assert (meshes, resolved) == (2 + pieces, 2 + pieces), "every mesh prim resolves its points"
    assert (colliders, guides) == (1 + pieces, pieces), "v's hull mesh and u's pieces collide; pieces are guides"
    assert readback.usd_errors(path) == []
    assert readback.usd_errors(compiled["decomposed"] / "usd" / "00000.usda") == []


def _json_objects(root: Path) -> dict[str, dict]:
    scene_file = next((root / "json").glob("*.json"))
    return {o["name"]: o for o in json.loads(scene_file.read_text())["objects"]}


def test_sizes_come_from_the_mesh_bounds_times_scale_unless_given(tmp_path):
    from prsc.commands.compile import compile_scenes

    _u_mesh(tmp_path / "u.obj")  # 0.1 x 0.05 x 0.06 m
    spec = tmp_path / "sizes.prs"
    spec.write_text('a = Object at Vector3D(0, 0, 1), with mesh "u.obj"\n'
                    'b = Object at Vector3D(1, 0, 1), with mesh "u.obj", with scale 2\n'
                    'c = Object at Vector3D(2, 0, 1), with mesh "u.obj", with scale 2, with height 0.5\n'
                    'd = Object at Vector3D(3, 0, 1), with mesh "u.obj", with scale Range(1, 3)\n')
    objects = _json_objects(compile_scenes(str(spec), ["json"], 1, 0, str(tmp_path / "out")))
    assert objects["a"]["shape"] == "mesh"  # `with mesh` alone asks for the mesh shape
    np.testing.assert_allclose(objects["a"]["dimensions"], [0.1, 0.05, 0.06], atol=1e-12)
    np.testing.assert_allclose(objects["b"]["dimensions"], [0.2, 0.1, 0.12], atol=1e-12)
    np.testing.assert_allclose(objects["c"]["dimensions"], [0.2, 0.1, 0.5], atol=1e-12)
    # One draw of a random scale serves all three sizes: the aspect ratio is the mesh's.
    d = np.asarray(objects["d"]["dimensions"])
    np.testing.assert_allclose(d / d[0], [1.0, 0.5, 0.6], atol=1e-12)
    assert 0.1 <= d[0] <= 0.3


def _check(spec: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "prsc.cli", "check", spec.name, *args], capture_output=True,
                          text=True, cwd=spec.parent, timeout=120)


def test_check_reports_a_missing_mesh_at_the_line_that_names_it_with_each_folder_once(tmp_path):
    spec = tmp_path / "mug.prs"
    spec.write_text('a = Object at Vector3D(0, 0, 1)\nmug = Object at Vector3D(1, 0, 1), with mesh "mugg.obj"\n')
    extra = tmp_path / "more"
    extra.mkdir()
    run = _check(spec, "-I", ".", "-I", "more")
    assert run.returncode == 2 and "Traceback" not in run.stderr
    first, source, caret = run.stderr.splitlines()[:3]
    assert first.startswith(f"{spec.name}:2:46: error: mug: mesh file 'mugg.obj' not found"), first
    assert source.strip() == 'mug = Object at Vector3D(1, 0, 1), with mesh "mugg.obj"'
    assert caret.strip() == "^" * len('"mugg.obj"') and caret.index("^") == source.index('"mugg.obj"')
    assert first.count(str(tmp_path)) == 2, "the spec's folder once (also given as -I .), then `more`"
    assert first.endswith(f"the spec's folder {tmp_path}, the --include folder {extra} "
                          f"or the model library {REPO / 'specs'}")


def test_check_rejects_an_unknown_collision_at_its_value(tmp_path):
    _u_mesh(tmp_path / "u.obj")
    spec = tmp_path / "c.prs"
    spec.write_text('u = Object at Vector3D(0, 0, 1), with mesh "u.obj", with collision "decompose"\n')
    run = _check(spec)
    assert run.returncode == 2
    assert "c.prs:1:68: error: unknown collision 'decompose' for a mesh (one of hull, decomposed); " \
           "did you mean 'decomposed'?" in run.stderr


def test_the_user_mesh_example_keeps_the_meshs_proportions():
    # compiled to every format and settled in tests/specs/test_example_specs.py
    from prsc.ir import compile_program
    from prsc.sampling import Sampler

    scene = Sampler(compile_program(str(REPO / "specs" / "user_mesh.prs")), "exact").sample(0, 0)
    cups = [o for o in scene.objects if o.props.get("mesh")]
    assert len(cups) == 3
    for cup in cups:  # the mesh's own proportions (80 x 80 x 95 mm at scale 0.001)
        np.testing.assert_allclose(np.asarray(cup.dims) / cup.props["scale"], [80, 80, 95], atol=1e-9)
