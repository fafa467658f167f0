"""A URDF of one link and no joints is a rigid object (docs/assets.md), free unless its root
link has mass 0 (pybullet's fixed base: its tray and table): pybullet's random_urdfs blobs
(whose inertia no simulator accepts: prsc takes it from the geometry, and says so) and its
tray, sized by their geometry, placed on a table, compiled to every format; in MuJoCo they
come to rest, and pybullet loads the blobs as free bodies."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.backends import readback

pybullet_data = pytest.importorskip("pybullet_data")
DATA = Path(pybullet_data.getDataPath())

SPEC = """\
from tabletop import *
table = Table on Vector3D(0, 0, 0), with width 1.2, with length 0.8, with height 0.75
class Blob:
    model: "random_urdfs/000/000.urdf"
class Blob7:
    model: "random_urdfs/007/007.urdf"
class UrdfTray:
    model: "tray/tray.urdf"
t = UrdfTray completely on table
a = Blob completely on table
b = Blob7 completely on table
"""


def test_one_link_urdfs_are_free_objects_in_every_format(tmp_path):
    spec = tmp_path / "objects.prs"
    spec.write_text(SPEC)
    done = subprocess.run([sys.executable, "-m", "prsc.cli", "compile", str(spec), "-I", str(DATA), "-n", "3",
                           "--target", "json,mjcf,urdf,sdf,usd", "-o", str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "000.urdf: links random_obj_000 have a mass or inertia no simulator accepts" in done.stderr
    root = tmp_path / "out" / "objects"
    for k in range(3):
        scene = json.loads((root / "json" / f"{k:05d}.json").read_text())
        objects = {o["name"]: o for o in scene["objects"]}
        assert not objects["a"]["static"] and objects["t"]["dimensions"][2] < 0.2  # a tray, not its mesh's box
        # tray_textured4.obj is five boxes, of which MuJoCo alone would read the first (one wall).
        assert objects["t"]["dimensions"] == pytest.approx(_tray_extent(), abs=1e-6)
        _come_to_rest(root / "mjcf" / f"{k:05d}.xml")
        poses, drops = readback.urdf_bundle_load(root / "urdf" / f"{k:05d}", visuals=False)
        readback.assert_poses(poses, scene, f"urdf scene {k}")
        readback.assert_free_fall(drops, scene, where=f"scene {k}: ")
        assert readback.usd_errors(root / "usd" / f"{k:05d}.usda") == []
    _keeps_the_urdf_colour(root, "a", DATA / "random_urdfs" / "000" / "000.urdf")
    _keeps_the_tray_texture(root)


def _keeps_the_tray_texture(root: Path) -> None:
    """The tray's OBJ names tray.jpg in its MTL: MuJoCo draws the tray with it, through its UVs,
    and its collision geoms (also drawn by MuJoCo's URDF import) are hidden behind nothing."""
    import mujoco

    model = mujoco.MjModel.from_xml_path(str(root / "mjcf" / "00000.xml"))
    tray = model.body("t").id
    geoms = [g for g in range(model.ngeom) if model.body_rootid[model.geom_bodyid[g]] == tray]
    seen = [g for g in geoms if model.geom_contype[g] == 0 and model.geom_conaffinity[g] == 0]
    assert seen and all(model.geom_group[g] == 3 for g in geoms if g not in seen)
    for g in seen:
        texture = model.mat_texid[model.geom_matid[g], mujoco.mjtTextureRole.mjTEXROLE_RGB]
        assert texture >= 0 and (model.tex_width[texture], model.tex_height[texture]) > (1, 1)
        assert model.mesh_texcoordnum[model.geom_dataid[g]] == model.mesh_vertnum[model.geom_dataid[g]]


def _come_to_rest(path: Path) -> None:
    """In MuJoCo, the tray and blob 007 stay where they are put; blob 000 rocks a few mm onto a
    stable side of its hull (its file's orientation is none) and stops."""
    import mujoco
    import numpy as np

    model = mujoco.MjModel.from_xml_path(str(path))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    names = ("t", "a", "b")
    start = [data.xpos[model.body(name).id].copy() for name in names]
    while data.time < 1.0:
        mujoco.mj_step(model, data)
    after_1s = [data.xpos[model.body(name).id].copy() for name in names]
    while data.time < 2.0:
        mujoco.mj_step(model, data)
    moved = {name: float(np.linalg.norm(data.xpos[model.body(name).id] - p)) for name, p in zip(names, start)}
    assert moved["t"] < 0.002 and moved["b"] < 0.002 and moved["a"] < 0.01, moved
    still = [float(np.linalg.norm(data.xpos[model.body(name).id] - p)) for name, p in zip(names, after_1s)]
    assert max(still) < 0.0005, still  # at rest after the first second


def _tray_extent() -> list[float]:
    """The extent of every object of the tray's OBJ, times the URDF's mesh scale 0.5 (trimesh reads them
    all), in the object's axes: the file's x along the object's y (LANGUAGE.md §7, "Forward")."""
    import trimesh

    x, y, z = (trimesh.load(DATA / "tray" / "tray_textured4.obj", force="mesh").extents * 0.5).tolist()
    return [y, x, z]


def _keeps_the_urdf_colour(root: Path, name: str, urdf: Path) -> None:
    """The object's visuals carry the colour of the URDF's own <material> in MJCF and USD."""
    import xml.etree.ElementTree as ET

    import mujoco
    from pxr import Usd, UsdGeom

    colour = [float(v) for v in ET.parse(urdf).find(".//material/color").get("rgba").split()]
    assert colour != [0.5, 0.5, 0.5, 1.0]  # not the default grey, so the check can fail
    model = mujoco.MjModel.from_xml_path(str(root / "mjcf" / "00000.xml"))
    body = model.body(name).id
    shown = [model.geom_rgba[g].tolist() for g in range(model.ngeom)
             if model.body_rootid[model.geom_bodyid[g]] == body]
    assert shown and all(abs(a - b) < 1e-6 for rgba in shown for a, b in zip(rgba, colour))
    stage = Usd.Stage.Open(str(root / "usd" / "00000.usda"))
    drawn = [UsdGeom.Gprim(p).GetDisplayColorAttr().Get() for p in Usd.PrimRange(stage.GetPrimAtPath(f"/World/{name}"))
             if p.IsA(UsdGeom.Gprim) and UsdGeom.Imageable(p).ComputePurpose() != UsdGeom.Tokens.guide]
    assert drawn and all(abs(c - d) < 1e-6 for value in drawn for c, d in zip(value[0], colour[:3]))


def test_a_massless_urdf_root_is_fixed_and_stands_on_its_visual_legs(tmp_path):
    """pybullet's table.urdf: its root link has mass 0 (pybullet's fixed base) and collides with its
    top only, its legs being visual. prsc keeps it static unless told otherwise, and its box is its
    whole geometry, so the legs stand on the floor and a cube `on` it rests on the top."""
    import mujoco

    spec = tmp_path / "table.prs"
    spec.write_text("from tabletop import *\nclass PbTable:\n    model: \"table/table.urdf\"\n"
                    "t = PbTable on Vector3D(0, 0, 0)\nc = Cube on t\nfree = PbTable on Vector3D(1.6, 0, 0), with static False\n")
    done = subprocess.run([sys.executable, "-m", "prsc.cli", "compile", str(spec), "-I", str(DATA), "-n", "1",
                           "--target", "json,mjcf", "-o", str(tmp_path / "out")], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    root = tmp_path / "out" / "table"
    objects = {o["name"]: o for o in json.loads((root / "json" / "00000.json").read_text())["objects"]}
    assert objects["t"]["static"] and not objects["free"]["static"]
    assert objects["t"]["dimensions"][2] == pytest.approx(0.625, abs=1e-6)  # legs 0.58 m and the top 0.05 m, from 0 to 0.625
    model = mujoco.MjModel.from_xml_path(str(root / "mjcf" / "00000.xml"))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    table = model.body("t").id
    lowest = min(data.geom_xpos[g][2] + (model.mesh_vert[model.mesh_vertadr[model.geom_dataid[g]]:
                                                          model.mesh_vertadr[model.geom_dataid[g]] + model.mesh_vertnum[model.geom_dataid[g]]]
                                         @ data.geom_xmat[g].reshape(3, 3).T)[:, 2].min()
                 for g in range(model.ngeom)
                 if model.body_rootid[model.geom_bodyid[g]] == table and model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH)
    assert lowest == pytest.approx(0.0, abs=1e-6)  # the legs' feet on the floor, not below it
    start = data.xpos[model.body("c").id].copy()
    for _ in range(300):
        mujoco.mj_step(model, data)
    assert start[2] == pytest.approx(0.625 + objects["c"]["dimensions"][2] / 2, abs=1e-3)
    assert abs(data.xpos[model.body("c").id][2] - start[2]) < 0.005  # rests on the top
