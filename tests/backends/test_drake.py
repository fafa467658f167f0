"""Drake loads the SDF world and the MJCF model of scenes with robots (pydrake's Parser).

Drake refuses a static SDF model with moving joints, skips MJCF `<frame>`s (and the robot
inside them) and reads only OBJ meshes from MJCF; these tests load real scenes of every
spec with a robot and read every object's pose back, check fixed objects and robots are
welded and free objects float, and that the whole arm arrived.
"""

from __future__ import annotations

import importlib.util
import json

import pytest

from tests.backends import readback
from tests.backends.scenes import every_model, rotated_robot
from tests.backends.specs import REPO

needs_drake = pytest.mark.skipif(
    importlib.util.find_spec("pydrake") is None, reason="pydrake (pip package drake, in the dev extras) not installed"
)

ROBOT_SPECS = ["table_cube", "shelf_bin", "facing_toward"]
SCENES = 3
ARM_LINKS = 13  # link0..link8, hand, two fingers, and the `base` body (MJCF) or the `tcp` link (SDF)


def _compiled(tmp_path, source, n=SCENES):
    from prsc.commands.compile import compile_scenes

    root = compile_scenes(str(source), ["json", "sdf", "mjcf"], n, 0, str(tmp_path / "out"))
    manifest = json.loads((root / "manifest.json").read_text())
    return root, [json.loads((root / s["files"]["json"]).read_text()) for s in manifest["scenes"]]


def _check(path, scene, fmt):
    plant, context, models = readback.drake_load(path)
    readback.assert_poses(readback.drake_poses(plant, context, models, scene), scene, fmt)
    floating = readback.drake_floating(plant, models, scene)
    for o in scene["objects"]:
        assert floating[o["name"]] == (not o["static"]), f"{fmt}: {o['name']} static={o['static']} but floating={floating[o['name']]}"
    robots = [o for o in scene["objects"] if o.get("model") == "panda"]
    extra = plant.num_bodies() - 1 - len(scene["objects"]) - (1 if fmt.startswith("sdf") and scene.get("ground", True) else 0)
    assert extra == ARM_LINKS * len(robots), f"{fmt}: {extra} robot bodies for {len(robots)} robots"
    return plant


@needs_drake
@pytest.mark.parametrize("spec", ROBOT_SPECS)
def test_drake_loads_sdf_and_mjcf_with_the_poses(spec, tmp_path):
    root, scenes = _compiled(tmp_path, REPO / "specs" / f"{spec}.prs")
    for k, scene in enumerate(scenes):
        _check(root / "sdf" / f"{k:05d}.sdf", scene, f"sdf scene {k}")
        _check(root / "mjcf" / f"{k:05d}.xml", scene, f"mjcf scene {k}")


@needs_drake
def test_drake_loads_a_yawed_robot_and_every_model(tmp_path):
    for name, scene in (("rotated_robot", rotated_robot()), ("every_model", every_model())):
        source = tmp_path / f"{name}.json"
        source.write_text(json.dumps(scene))
        root, scenes = _compiled(tmp_path / name, source, n=1)
        _check(root / "sdf" / "00000.sdf", scenes[0], f"sdf {name}")
        _check(root / "mjcf" / "00000.xml", scenes[0], f"mjcf {name}")


@needs_drake
def test_drake_welds_a_fixed_robot_and_moves_its_joints(tmp_path):
    """The SDF robot is welded to the world (not static, not floating) with 9 moving joints."""
    root, scenes = _compiled(tmp_path, REPO / "specs" / "table_cube.prs", n=1)
    plant, _, models = readback.drake_load(root / "sdf" / "00000.sdf")
    r1 = next(m for m in models if plant.GetModelInstanceName(m) == "r1")
    assert plant.num_positions(r1) == 9 and not plant.GetBodyByName("r1", r1).is_floating_base_body()
    assert plant.GetJointByName("r1_world_weld").type_name() == "weld"


def test_pybullet_keeps_the_welded_robot_fixed(tmp_path):
    """pybullet skips the world-level weld; the massless mount is what fixes the base there."""
    import pybullet as p

    root, scenes = _compiled(tmp_path, REPO / "specs" / "table_cube.prs", n=1)
    client = p.connect(p.DIRECT)
    try:
        p.setGravity(0, 0, -9.81, physicsClientId=client)
        bodies = {p.getBodyInfo(b, physicsClientId=client)[1].decode(): b
                  for b in p.loadSDF(str(root / "sdf" / "00000.sdf"), physicsClientId=client)}
        start = {n: p.getBasePositionAndOrientation(bodies[n], physicsClientId=client)[0] for n in ("r1", "r2")}
        for _ in range(240):
            p.stepSimulation(physicsClientId=client)
        for name in ("r1", "r2"):
            end = p.getBasePositionAndOrientation(bodies[name], physicsClientId=client)[0]
            assert max(abs(a - b) for a, b in zip(start[name], end)) < 1e-9, f"{name} base moved in pybullet"
            assert p.getNumJoints(bodies[name], physicsClientId=client) > 9
    finally:
        p.disconnect(client)
