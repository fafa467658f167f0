"""A `Light` (LANGUAGE.md §6): random pose, colour, intensity and cone, written to every format
and set by `scenario.apply` per scene as a freshly compiled model has it.

- 10 scenes through `apply`: `light_pos`, `light_dir`, `light_diffuse`, `light_cutoff` (and what
  mj_setConst derives) equal a fresh model's, and they change from scene to scene;
- MuJoCo loads the MJCF file with the light; pxr's validators report 0 errors on the USD
  stage; pybullet and Drake load the SDF world (Drake also the MJCF); the URDF bundle's scene.json lists the light;
- a light has no body in any format (it collides with nothing).
"""

from __future__ import annotations

import json
from pathlib import Path

import mujoco
import numpy as np
import pytest

import prsc
from tests.backends import readback

SPEC = """from tabletop import *
table = Table on Vector3D(0, 0, 0), with width 1.2, with length 0.8, with height 0.75
c1 = Cube completely on table
lamp = Light at Vector3D((-0.3, 0.3), (-0.3, 0.3), (1.5, 2.0)), facing Vector3D((-0.3, 0.3), 1, -1),
    with color [(0.6, 1.0), (0.6, 1.0), (0.6, 1.0)], with intensity (0.5, 1.5), with kind "spot", with cutoff (20, 60)
sun = Light at Vector3D(0, 0, 3), facing Vector3D(0, 0.2, -1), with castShadow True
"""
LIGHT_ARRAYS = ("light_pos", "light_dir", "light_diffuse", "light_cutoff", "light_castshadow", "light_type",
                "light_pos0", "light_dir0", "light_poscom0")


@pytest.fixture(scope="module")
def spec(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("lights") / "lamps.prs"
    path.write_text(SPEC)
    return path


def test_apply_sets_each_scene_s_lights_as_a_fresh_model(spec):
    scenario = prsc.load(spec)
    model = scenario.model()
    data = mujoco.MjData(model)
    assert model.nlight == 3  # prsc's own sun and the spec's two
    worst = dict.fromkeys(LIGHT_ARRAYS, 0.0)
    seen = set()
    for index in range(1, 11):
        scene = scenario.scene(0, index)
        scenario.apply(scene, model, data)
        fresh = prsc.mujoco_model(scene)
        for name in LIGHT_ARRAYS:
            error = np.max(np.abs(getattr(model, name).astype(float) - getattr(fresh, name).astype(float)))
            worst[name] = max(worst[name], float(error))
        lamp = model.light("lamp").id
        seen.add((tuple(model.light_pos[lamp]), tuple(model.light_dir[lamp]), tuple(model.light_diffuse[lamp])))
    assert {name: error for name, error in worst.items() if error > 1e-12} == {}
    assert len(seen) == 10  # position, direction and colour are drawn per scene
    assert model.light_type[model.light("lamp").id] == mujoco.mjtLightType.mjLIGHT_SPOT
    assert model.light_castshadow[model.light("sun").id] and not model.light_castshadow[model.light("lamp").id]


def test_every_format_loads_the_lights(spec, tmp_path):
    from prsc.cli import main

    assert main(["compile", str(spec), "--target", "mjcf,usd,sdf,urdf", "-n", "1", "-o", str(tmp_path)]) == 0
    out = tmp_path / "lamps"
    model = mujoco.MjModel.from_xml_path(str(out / "mjcf" / "00000.xml"))
    assert model.nlight == 3 and model.nbody == 3  # the world, the table and the cube: a light is no body
    assert readback.usd_errors(out / "usd" / "00000.usda") == []
    from pxr import Usd, UsdLux

    stage = Usd.Stage.Open(str(out / "usd" / "00000.usda"))
    assert stage.GetPrimAtPath("/World/lamp/light").IsA(UsdLux.SphereLight)
    assert stage.GetPrimAtPath("/World/sun/light").IsA(UsdLux.DistantLight)
    poses = readback.sdf_poses(out / "sdf" / "00000.sdf")
    assert "lamp" not in poses and {"table", "c1"} <= set(poses)
    pytest.importorskip("pydrake")
    for written in (out / "sdf" / "00000.sdf", out / "mjcf" / "00000.xml"):  # Drake ignores lights, with a warning
        plant, _, models = readback.drake_load(written)
        assert plant.HasBodyNamed("c1") and not plant.HasBodyNamed("lamp")
    bundle = json.loads((out / "urdf" / "00000" / "scene.json").read_text())
    assert [light["name"] for light in bundle["lights"]] == ["lamp", "sun"]
    assert "lamp" not in [o["name"] for o in bundle["objects"]]
