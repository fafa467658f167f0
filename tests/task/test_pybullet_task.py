"""The same task file scored from pybullet: the three cases of tests/task/test_mujoco_task.py, in a
pybullet world built from the scene JSON (table, the tray's floor and walls, the cube), and in the
SDF world `prsc compile` wrote, loaded with its task file by `PybulletTask.load` as docs/tasks.md
shows (and the URDF bundle's, which must load the same poses)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pybullet
import pytest
from scipy.spatial.transform import Rotation

import prsc
from prsc.geometry.container import declared_interior
from prsc.task.pybullet_adapter import PybulletTask

SPEC = Path(__file__).with_name("tray_task.prs")
DT = 0.002


@pytest.fixture(scope="module")
def scene():
    return prsc.load(SPEC).scene(0, 0)


@pytest.fixture(scope="module")
def compiled(tmp_path_factory):
    """The spec's scene 0 as `prsc compile` writes it: SDF world and URDF bundle, each with its task file."""
    from prsc.cli import main

    out = tmp_path_factory.mktemp("compiled")
    assert main(["compile", str(SPEC), "--target", "sdf,urdf", "-n", "1", "-o", str(out)]) == 0
    return out / "tray_task"


def _box(client, half, position, mass, parts=None):
    if parts is None:
        shape = pybullet.createCollisionShape(pybullet.GEOM_BOX, halfExtents=half, physicsClientId=client)
    else:  # a compound: the tray's floor and walls, in its box frame
        shape = pybullet.createCollisionShapeArray([pybullet.GEOM_BOX] * len(parts), halfExtents=[h for h, _ in parts],
                                                   collisionFramePositions=[c for _, c in parts], physicsClientId=client)
    return pybullet.createMultiBody(mass, shape, basePosition=position, physicsClientId=client)


def _world(scene):
    client = pybullet.connect(pybullet.DIRECT)
    pybullet.setGravity(0, 0, -9.81, physicsClientId=client)
    pybullet.setTimeStep(DT, physicsClientId=client)
    objects = {o["name"]: o for o in scene["objects"]}
    bodies = {}
    for name in ("table", "cube"):
        o = objects[name]
        bodies[name] = _box(client, [d / 2 for d in o["dimensions"]], o["position"], 0.0 if o["static"] else o["mass"])
    tray = objects["tray"]
    interior = declared_interior(tuple(tray["dimensions"]), tray["properties"])
    w, l, h = tray["dimensions"]
    t, f = interior.wall, interior.floor
    parts = [([w / 2, l / 2, f / 2], [0, 0, -h / 2 + f / 2]),
             ([t / 2, l / 2, h / 2], [w / 2 - t / 2, 0, 0]), ([t / 2, l / 2, h / 2], [-w / 2 + t / 2, 0, 0]),
             ([w / 2, t / 2, h / 2], [0, l / 2 - t / 2, 0]), ([w / 2, t / 2, h / 2], [0, -l / 2 + t / 2, 0])]
    bodies["tray"] = _box(client, None, tray["position"], tray["mass"], parts)
    return client, bodies


def _run(scene, script, seconds, compiled=None):
    """The task's record after `seconds` of the script; in the compiled SDF world when given."""
    if compiled is None:
        client, bodies = _world(scene)
        task = PybulletTask(scene["task"], bodies, client)
    else:
        client = pybullet.connect(pybullet.DIRECT)
        pybullet.setGravity(0, 0, -9.81, physicsClientId=client)
        pybullet.setTimeStep(DT, physicsClientId=client)
        task = PybulletTask.load(compiled / "sdf" / "00000.sdf", client)
        bodies = task.bodies
    try:
        steps_per_update = 10  # 0.02 s, the runner's control period
        for k in range(int(round(seconds / DT))):
            target = script(k * DT)
            if target is not None:
                pybullet.resetBasePositionAndOrientation(bodies["cube"], target, [0, 0, 0, 1], physicsClientId=client)
                pybullet.resetBaseVelocity(bodies["cube"], [0, 0, 0], [0, 0, 0], physicsClientId=client)
            pybullet.performCollisionDetection(physicsClientId=client)
            if k % steps_per_update == 0:
                task.update(k * DT)
            pybullet.stepSimulation(physicsClientId=client)
        return task.result(seconds, controller_finished=True)
    finally:
        pybullet.disconnect(client)


def _floor(scene):
    from tests.task.test_mujoco_task import tray_floor_point

    return tray_floor_point(scene)


WORLDS = ["built from the scene JSON", "compiled SDF"]


def _world_of(kind, request):
    return request.getfixturevalue("compiled") if kind == "compiled SDF" else None


@pytest.mark.parametrize("kind", WORLDS)
def test_carried_above_the_tray_is_no_success_in_pybullet(scene, kind, request):
    above = _floor(scene) + [0, 0, 0.05]
    result = _run(scene, lambda t: above, 1.5, _world_of(kind, request))
    assert result["outcome"] == "incomplete" and result["robustness"]["goal"] < 0


@pytest.mark.parametrize("kind", WORLDS)
def test_in_and_out_is_no_success_in_pybullet(scene, kind, request):
    inside = _floor(scene)
    result = _run(scene, lambda t: inside if 0.3 < t < 0.6 else inside + [-0.25, 0, 0] if t >= 0.6 else inside + [0, 0, 0.1], 1.5,
                  _world_of(kind, request))
    assert result["outcome"] == "incomplete" and result["robustness"]["goal"] <= 0


@pytest.mark.parametrize("kind", WORLDS)
def test_resting_in_the_tray_is_a_success_in_pybullet(scene, kind, request):
    inside = _floor(scene)
    result = _run(scene, lambda t: inside + [0, 0, 0.02] if t < 0.1 else None, 2.0, _world_of(kind, request))
    assert result["outcome"] == "success" and result["robustness"]["goal"] > 0
    assert result["records"]["inside"] is True and np.allclose(result["records"]["start"][2], inside[2] + 0.02, atol=1e-6)


@pytest.mark.parametrize("output", ["sdf/00000.sdf", "urdf/00000"])
def test_load_reads_the_task_file_and_the_objects_box_frames(scene, compiled, output):
    """`load` finds the scene's task file and reports each object at its box frame (pybullet's base
    position is the centre of mass: the table's is 0.31 m above its box centre)."""
    client = pybullet.connect(pybullet.DIRECT)
    try:
        task = PybulletTask.load(compiled / output, client)
        assert task.task.to_json() == scene["task"]
        state = task.state(0.0)
        for o in scene["objects"]:
            pose = state.poses[o["name"]]
            assert np.allclose(pose.position, o["position"], atol=1e-6), o["name"]
            w, x, y, z = o["quaternion"]
            assert np.allclose(pose.rotation, Rotation.from_quat([x, y, z, w]).as_matrix(), atol=1e-6)
        table = task.bodies["table"]
        assert pybullet.getBasePositionAndOrientation(table, physicsClientId=client)[0][2] > scene["objects"][0]["position"][2] + 0.1
    finally:
        pybullet.disconnect(client)


def test_the_docs_example_runs_as_written(compiled, capsys):
    """docs/tasks.md's pybullet block, on the compiled SDF world: the cube stays on the table, so the
    task times out at `terminate after 3 seconds`."""
    import re

    text = (Path(__file__).parents[2] / "docs" / "tasks.md").read_text()
    block = next(b for b in re.findall(r"```python\n(.*?)```", text, re.S) if "PybulletTask.load" in b)
    code = block.replace('"out/spec/', f'"{compiled}/').replace("00003", "00000")  # the one scene compiled
    try:
        exec(compile(code, "docs/tasks.md", "exec"), {})
    finally:
        pybullet.disconnect()
    out = capsys.readouterr().out
    assert "'outcome': 'timeout'" in out, out


def test_a_robot_on_the_table_is_scored_as_in_mujoco(tmp_path):
    """table_cube through its SDF world: a mounted arm touches with its moving links only (its base
    stands on the table, as in MuJoCo), its fingers are found by name, and each statement's
    robustness at the start matches MuJoCo's monitor on the MJCF to 5 mm."""
    import json

    from prsc.cli import main
    from prsc.runner.harness import fresh_data, load_model
    from prsc.runner.task_monitor import TaskMonitor

    spec = Path(__file__).parents[2] / "specs" / "table_cube.prs"
    assert main(["compile", str(spec), "--target", "json,mjcf,sdf", "-n", "1", "-o", str(tmp_path)]) == 0
    root = tmp_path / "table_cube"
    model = load_model(root / "mjcf" / "00000.xml")
    in_mujoco = TaskMonitor(json.loads((root / "json" / "00000.json").read_text()), model).update(model, fresh_data(model))
    client = pybullet.connect(pybullet.DIRECT)
    try:
        task = PybulletTask.load(root / "sdf" / "00000.sdf", client)
        in_pybullet = task.update(0.0)
        assert sorted(task.links) == [f"{r}/panda_{side}finger" for r in ("r1", "r2") for side in ("left", "right")]
    finally:
        pybullet.disconnect(client)
    assert in_mujoco.robustness["fail:arm on table"] > 0.1  # the arms start clear of the table top
    for label, value in in_mujoco.robustness.items():
        assert abs(in_pybullet.robustness[label] - value) < 0.005, (label, in_pybullet.robustness, in_mujoco.robustness)
