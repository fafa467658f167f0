"""Articulated furniture (docs/assets.md, "Links"): the tests' own cabinet (URDF and MJCF) with a drawer
pulled out to a sampled value, a cube `completely in` the drawer and one `completely on` the
carcass. The drawer's value is the MJCF `home` key's, the cube rests on the drawer's floor
inside its walls, and a gentle pull moves the drawer with the cube riding along; links
that do not exist or are not hollow are errors `prsc check` reports at their line."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.backends import readback

DATA = Path(__file__).resolve().parent / "data"
SCENES = 10
SPEC = """\
from tabletop import *

class Cabinet:
    model: "cabinet.urdf"

cab = Cabinet on Vector3D(0, 0, 0), with joint "drawer_slide" (0.05, 0.2)
cube = Cube completely in cab.links["drawer"], with color "red"
box = Cube completely on cab.links["carcass"], with color "blue"
"""
FLOOR = (-0.21, 0.21, -0.17, 0.18, 0.01)  # the drawer's floor inside its walls (x, x, y, y, z in its frame)


def _prsc(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "prsc.cli", *args], capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module", params=["cabinet.urdf", "cabinet.xml"])
def compiled(request, tmp_path_factory) -> Path:
    """The same cabinet as the tests' URDF and as their MJCF, compiled to every format."""
    folder = tmp_path_factory.mktemp("cabinet")
    shutil.copy(DATA / request.param, folder / request.param)
    (folder / "cab.prs").write_text(SPEC.replace("cabinet.urdf", request.param))
    done = _prsc("compile", str(folder / "cab.prs"), "-n", str(SCENES), "--target", "json,mjcf,urdf,sdf,usd",
                 "-o", str(folder / "out"))
    assert done.returncode == 0, done.stdout + done.stderr
    return folder / "out" / "cab"


def test_the_home_key_holds_the_drawer_at_the_scene_value(compiled):
    values = []
    for k in range(SCENES):
        scene, model, data = readback.scene_at_home(compiled, k)
        cab = next(o for o in scene["objects"] if o["name"] == "cab")
        value = cab["joints"]["drawer_slide"]
        assert 0.05 <= value <= 0.2
        assert data.qpos[model.joint("cab/drawer_slide").qposadr[0]] == pytest.approx(value, abs=1e-12)
        assert cab["static"] and "tcp" not in cab["properties"]  # fixed furniture, no robot
        assert model.nu == 0  # no servo holds a cabinet's drawer
        values.append(value)
    assert len(set(values)) == SCENES  # drawn per scene


def test_the_cube_rests_on_the_drawer_floor_inside_its_walls(compiled):
    import mujoco

    for k in range(SCENES):
        scene, model, data = readback.scene_at_home(compiled, k)
        cube = next(o for o in scene["objects"] if o["name"] == "cube")
        drawer = model.body("cab/drawer").id
        frame = data.xmat[drawer].reshape(3, 3)
        local = frame.T @ (np.asarray(cube["position"]) - data.xpos[drawer])
        half = np.asarray(cube["dimensions"]) / 2
        x0, x1, y0, y1, z = FLOOR
        assert x0 - 1e-9 <= local[0] - half[0] and local[0] + half[0] <= x1 + 1e-9, (k, local)
        assert y0 - 1e-9 <= local[1] - half[1] and local[1] + half[1] <= y1 + 1e-9, (k, local)
        assert local[2] - half[2] == pytest.approx(z, abs=1e-9)
        body = model.body("cube").id
        start = data.xpos[body].copy()
        while data.time < 1.0:
            mujoco.mj_step(model, data)
        assert np.linalg.norm(data.xpos[body] - start) < 0.002, k


def test_a_gentle_pull_moves_the_drawer_and_the_cube_rides_along(compiled):
    import mujoco

    for k in range(SCENES):
        _, model, data = readback.scene_at_home(compiled, k)
        joint = model.joint("cab/drawer_slide").qposadr[0]
        drawer, cube = model.body("cab/drawer").id, model.body("cube").id
        while data.time < 0.5:
            mujoco.mj_step(model, data)
        drawer_start, cube_start, opened = data.xpos[drawer].copy(), data.xpos[cube].copy(), data.qpos[joint]
        while data.qpos[joint] < opened + 0.02:  # 1 N along the drawer's axis until it has moved 2 cm
            data.xfrc_applied[drawer, :3] = data.xmat[drawer].reshape(3, 3) @ np.array([0.0, 1.0, 0.0])
            mujoco.mj_step(model, data)
        data.xfrc_applied[:] = 0.0
        stop = data.time + 2.0
        while data.time < stop:
            mujoco.mj_step(model, data)
        moved = data.xpos[drawer] - drawer_start
        assert np.linalg.norm(moved) > 0.02, k
        assert np.linalg.norm((data.xpos[cube] - cube_start) - moved) < 0.01, k


def test_every_format_carries_the_cabinet(compiled):
    from pxr import Usd, UsdGeom, UsdPhysics

    for k in range(2):
        assert readback.usd_errors(compiled / "usd" / f"{k:05d}.usda") == []
        # USD: the drawer where the scene's joint value puts it (as in MuJoCo), drawn with the
        # URDF's boxes, its joint free (no drive holds furniture).
        _, model, data = readback.scene_at_home(compiled, k)
        stage = Usd.Stage.Open(str(compiled / "usd" / f"{k:05d}.usda"))
        drawer = next(p for p in stage.Traverse() if p.GetName() == "drawer")
        placed = UsdGeom.XformCache().GetLocalToWorldTransform(drawer).ExtractTranslation()
        assert np.allclose(placed, data.xpos[model.body("cab/drawer").id], atol=1e-6)
        assert sum(1 for p in Usd.PrimRange(drawer) if p.IsA(UsdGeom.Cube)) == 10  # 5 boxes, seen and colliding
        slide = next(p for p in stage.Traverse() if p.GetName() == "drawer_slide")
        assert slide.IsA(UsdPhysics.PrismaticJoint) and not slide.HasAPI(UsdPhysics.DriveAPI)
        # Newton starts the drawer at the scene's value, with the links where the stage draws them.
        loaded = readback.newton_load(compiled / "usd" / f"{k:05d}.usda")
        value = data.qpos[model.joint("cab/drawer_slide").qposadr[0]]
        assert loaded["joints"]["drawer_slide"] == pytest.approx(value, abs=1e-6)
        assert loaded["fk_gap"] < 1e-5 and {"cube", "box"} <= loaded["free"]
        readback.urdf_validate(compiled / "urdf" / f"{k:05d}")
        poses = readback.sdf_poses(compiled / "sdf" / f"{k:05d}.sdf")
        assert {"cab", "cube", "box"} <= set(poses)


@pytest.mark.parametrize("line, message", [
    ('cube = Cube completely in cab.links["drawr"]', "has no link 'drawr'"),
    ('cube = Cube completely in cab.links["carcass"]', "needs a hollow link"),
    ('cube = Cube completely in t.links["drawer"]', "t has no links"),
])
def test_check_reports_a_bad_link_at_its_line(tmp_path, line, message):
    shutil.copy(DATA / "cabinet.urdf", tmp_path / "cabinet.urdf")
    text = SPEC.replace('cube = Cube completely in cab.links["drawer"], with color "red"', line)
    text = text.replace("cab = Cabinet", "t = Table on Vector3D(0, 1.5, 0)\ncab = Cabinet")
    (tmp_path / "cab.prs").write_text(text)
    line_number = text.splitlines().index(line) + 1
    for command in ("check", "compile"):
        done = _prsc(command, str(tmp_path / "cab.prs"), *(["-o", str(tmp_path / "out")] if command == "compile" else []))
        assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
        assert f"cab.prs:{line_number}:" in done.stderr and message in done.stderr, done.stderr
    assert not (tmp_path / "out").exists()


def test_a_drawer_of_one_collision_mesh_is_refused_and_the_error_says_why(tmp_path):
    """A drawer whose floor and walls are one collision mesh collides as that mesh's convex hull
    in MuJoCo (a solid block): `in` it is an error at its line that says so."""
    import re

    import trimesh

    urdf = (DATA / "cabinet.urdf").read_text()
    drawer = urdf[urdf.index('<link name="drawer">'):urdf.index("</link>", urdf.index('<link name="drawer">'))]
    parts = []
    for origin, size in re.findall(r'<collision><origin xyz="([^"]+)"/><geometry><box size="([^"]+)"/>', drawer):
        box = trimesh.creation.box(extents=[float(v) for v in size.split()])
        box.apply_translation([float(v) for v in origin.split()])
        parts.append(box)
    assert len(parts) == 5  # the floor and four walls
    trimesh.util.concatenate(parts).export(tmp_path / "drawer.obj")
    one_mesh = re.sub(r"<collision>.*?</collision>", "", drawer, flags=re.S)
    one_mesh = one_mesh.replace("</inertial>", '</inertial>\n    <collision><geometry><mesh filename="drawer.obj"/>'
                                "</geometry></collision>", 1)
    (tmp_path / "cabinet.urdf").write_text(urdf.replace(drawer, one_mesh))
    (tmp_path / "cab.prs").write_text(SPEC)
    line = SPEC.splitlines().index('cube = Cube completely in cab.links["drawer"], with color "red"') + 1
    for command in ("check", "compile"):
        done = _prsc(command, str(tmp_path / "cab.prs"), *(["-o", str(tmp_path / "out")] if command == "compile" else []))
        assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
        assert f"cab.prs:{line}:" in done.stderr and "needs a hollow link" in done.stderr, done.stderr
        assert "1 of its collision geoms is a mesh: MuJoCo collides a mesh as its convex hull" in done.stderr
    assert not (tmp_path / "out").exists()


LIBRARY_SPEC = """\
from tabletop import *

cab = DrawerCabinet on Vector3D(0, 0, 0), with drawers 4, with width 0.8, with joint "drawer2_slide" (0.1, 0.25)
cube = Cube completely in cab.links["drawer2"], with color "red"
"""


def test_the_library_cabinet_has_its_drawers_and_holds_a_cube_in_one(tmp_path):
    (tmp_path / "lib.prs").write_text(LIBRARY_SPEC)
    done = _prsc("compile", str(tmp_path / "lib.prs"), "-n", "3", "--target", "json,mjcf,urdf,usd",
                 "-o", str(tmp_path / "out"), "--settle-check")
    assert done.returncode == 0 and "3 of 3 scenes at rest" in done.stdout, done.stdout + done.stderr
    root = tmp_path / "out" / "lib"
    for k in range(3):
        scene, model, data = readback.scene_at_home(root, k)
        cab = next(o for o in scene["objects"] if o["name"] == "cab")
        assert cab["dimensions"] == pytest.approx([0.8, 0.45, 0.75], abs=1e-9)  # the box the numbers ask for
        assert sorted(cab["joints"]) == [f"drawer{d}_slide" for d in range(4)]
        assert [model.jnt_range[model.joint(f"cab/drawer{d}_slide").id][1] for d in range(4)] == \
            pytest.approx([0.8 * (0.45 - 0.018 - 0.004)] * 4)
        drawer = model.body("cab/drawer2").id
        cube = model.body("cube").id
        local = data.xmat[drawer].reshape(3, 3).T @ (data.xpos[cube] - data.xpos[drawer])
        assert local[2] == pytest.approx(0.008 + 0.02, abs=1e-6)  # on the floor (8 mm) of drawer2, the cube 4 cm
        assert readback.usd_errors(root / "usd" / f"{k:05d}.usda") == []
        readback.urdf_validate(root / "urdf" / f"{k:05d}")


def test_a_library_cabinet_without_drawers_is_an_error_at_its_line(tmp_path):
    (tmp_path / "lib.prs").write_text(LIBRARY_SPEC.replace("with drawers 4", "with drawers 0"))
    done = _prsc("check", str(tmp_path / "lib.prs"))
    assert done.returncode == 2 and "lib.prs:3:" in done.stderr and "1 to 8 drawers" in done.stderr, done.stderr


def test_the_example_spec_compiles_and_rests(tmp_path):
    spec = Path(__file__).resolve().parents[2] / "specs" / "furniture" / "drawer_cubes.prs"
    done = _prsc("compile", str(spec), "-n", "2", "--target", "json,mjcf", "-o", str(tmp_path / "out"), "--settle-check")
    assert done.returncode == 0 and "2 of 2 scenes at rest" in done.stdout, done.stdout + done.stderr


def test_names_usd_does_not_allow_become_valid_prim_names(tmp_path):
    """URDF names may hold `-` and `.`; USD prim names may not: the stage uses valid ones and
    still validates, and Newton loads the drawer's joint at the scene's value."""
    from pxr import Usd, UsdPhysics

    urdf = (DATA / "cabinet.urdf").read_text().replace('"drawer"', '"drawer-1"').replace("drawer_slide", "drawer.slide")
    (tmp_path / "cabinet.urdf").write_text(urdf)
    spec = SPEC.replace('"drawer"]', '"drawer-1"]').replace("drawer_slide", "drawer.slide")
    (tmp_path / "cab.prs").write_text(spec)
    done = _prsc("compile", str(tmp_path / "cab.prs"), "-n", "1", "--target", "json,usd", "-o", str(tmp_path / "out"))
    assert done.returncode == 0, done.stdout + done.stderr
    usd = tmp_path / "out" / "cab" / "usd" / "00000.usda"
    assert readback.usd_errors(usd) == []
    stage = Usd.Stage.Open(str(usd))
    names = {p.GetName(): p for p in stage.Traverse()}
    assert "drawer_1" in names and names["drawer_slide"].IsA(UsdPhysics.PrismaticJoint)
    value = json.loads((tmp_path / "out" / "cab" / "json" / "00000.json").read_text())["objects"][0]["joints"]
    assert readback.newton_load(usd)["joints"]["drawer_slide"] == pytest.approx(value["drawer.slide"], abs=1e-6)
