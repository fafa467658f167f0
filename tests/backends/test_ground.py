"""The ground: one finite size in every format, collided as an infinite plane by MuJoCo (its size
only sets what is drawn, and keeps a render context independent of stat.extent: docs/learning.md)."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import mujoco
import numpy as np

from prsc.backends.scene import GROUND_HALF_SIZE
from prsc.cli import main
from tests.backends import readback
from tests.backends.scenes import obj, scene


def test_every_format_writes_the_same_finite_ground(tmp_path):
    source = tmp_path / "g.json"
    source.write_text(json.dumps(scene([obj("cube", "Cube", (0.0, 0.0, 0.05), (0.1, 0.1, 0.1))])))
    assert main(["compile", str(source), "--target", "mjcf,urdf,sdf,usd", "-o", str(tmp_path / "out")]) == 0
    root, edge = tmp_path / "out" / "g", 2 * GROUND_HALF_SIZE
    model = readback.mjcf_model(root / "mjcf" / "00000.xml")
    ground = model.geom("ground")
    assert ground.type[0] == mujoco.mjtGeom.mjGEOM_PLANE and list(ground.size[:2]) == [GROUND_HALF_SIZE] * 2
    sizes = {e.text for e in ET.parse(root / "sdf" / "00000.sdf").iter("size")}
    assert f"{edge:g} {edge:g}" in sizes
    slab = ET.parse(root / "urdf" / "00000" / "ground.urdf").find(".//collision/geometry/box")
    assert [float(v) for v in slab.get("size").split()[:2]] == [edge, edge]
    usd = (root / "usd" / "00000.usda").read_text()
    assert f"double width = {edge:g}" in usd and f"double length = {edge:g}" in usd
    # Collided as infinite: a sphere dropped 3 m beyond the drawn ground's edge comes to rest on it.
    spec = mujoco.MjSpec.from_file(str(root / "mjcf" / "00000.xml"))
    body = spec.worldbody.add_body(pos=[GROUND_HALF_SIZE + 3, 0, 0.3])
    body.add_freejoint()
    body.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.05, 0, 0])
    far = spec.compile()
    data = mujoco.MjData(far)
    mujoco.mj_step(far, data, nstep=int(1.0 / far.opt.timestep))
    assert np.isclose(data.xpos[-1][2], 0.05, atol=2e-3) and abs(data.xpos[-1][0] - GROUND_HALF_SIZE - 3) < 1e-3
