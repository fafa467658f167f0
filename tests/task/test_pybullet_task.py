"""The same task.json scored from pybullet: the three cases of tests/task/test_mujoco_task.py, in a
pybullet world built from the scene JSON (table, the tray's floor and walls, the cube)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pybullet
import pytest

import prsc
from prsc.geometry.container import declared_interior
from prsc.task.pybullet_adapter import PybulletTask

SPEC = Path(__file__).with_name("tray_task.prs")
DT = 0.002


@pytest.fixture(scope="module")
def scene():
    return prsc.load(SPEC).scene(0, 0)


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


def _run(scene, script, seconds):
    client, bodies = _world(scene)
    try:
        task = PybulletTask(scene["task"], bodies, client)
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


def test_carried_above_the_tray_is_no_success_in_pybullet(scene):
    above = _floor(scene) + [0, 0, 0.05]
    result = _run(scene, lambda t: above, 1.5)
    assert result["outcome"] == "incomplete" and result["robustness"]["goal"] < 0


def test_in_and_out_is_no_success_in_pybullet(scene):
    inside = _floor(scene)
    result = _run(scene, lambda t: inside if 0.3 < t < 0.6 else inside + [-0.25, 0, 0] if t >= 0.6 else inside + [0, 0, 0.1], 1.5)
    assert result["outcome"] == "incomplete" and result["robustness"]["goal"] <= 0


def test_resting_in_the_tray_is_a_success_in_pybullet(scene):
    inside = _floor(scene)
    result = _run(scene, lambda t: inside + [0, 0, 0.02] if t < 0.1 else None, 2.0)
    assert result["outcome"] == "success" and result["robustness"]["goal"] > 0
    assert result["records"]["inside"] is True and np.allclose(result["records"]["start"][2], inside[2] + 0.02, atol=1e-6)
