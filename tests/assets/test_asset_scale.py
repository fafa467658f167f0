"""`scale` on an asset from a file (docs/assets.md, "Size"): pybullet's xArm6 URDF at half
size, the tests' MJCF arm at twice its size and pybullet's table at 0.3, compiled to every
format. Each box is the file's times the scale; in MuJoCo every length of the tree scales
(the tool's distance from the base at home), masses scale by s^3; the scaled xArm holds its
pose under its servos and the small table stands on its legs on the big one. A random or
non-positive scale is an error at its value, from `check`."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from tests.assets.test_user_arms import MJCF_ARM
from tests.backends import readback

pybullet_data = pytest.importorskip("pybullet_data")
DATA = Path(pybullet_data.getDataPath())
SPEC = """\
from tabletop import *
class XArm(Robot):
    model: "xarm/xarm6_robot.urdf"
    scale: 0.5
class Lab(Robot):
    model: "arm.xml"
class SmallTable:
    model: "table/table.urdf"
table = Table on Vector3D(0, 0, 0), with width 1.8, with length 1.2, with height 0.75
arm = XArm on (top back table).position + Vector3D(0.3, 0.25, 0), with joint "joint3" -0.6
lab = Lab on (top back table).position + Vector3D(-0.5, 0.25, 0), with scale 2
small = SmallTable completely on table, with scale 0.3
"""


def _prsc(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "prsc.cli", *args], capture_output=True, text=True, cwd=cwd, timeout=600)


@pytest.fixture(scope="module")
def compiled(tmp_path_factory):
    folder = tmp_path_factory.mktemp("scaled")
    (folder / "arm.xml").write_text(MJCF_ARM)
    (folder / "s.prs").write_text(SPEC)
    done = _prsc("compile", "s.prs", "-I", str(DATA), "-n", "1", "--target", "json,mjcf,urdf,sdf,usd", "-o", "out", cwd=folder)
    assert done.returncode == 0, done.stderr
    assert "Attach conflict" not in done.stderr
    scene = json.loads((folder / "out" / "s" / "json" / "00000.json").read_text())
    return folder, folder / "out" / "s", {o["name"]: o for o in scene["objects"]}


def _alone(path: Path):
    """The asset file compiled alone in MuJoCo, at its home."""
    import mujoco

    from prsc.user_assets.asset_files import asset_spec

    model = asset_spec(path, [str(DATA)]).compile()
    data = mujoco.MjData(model)
    if model.nkey:
        mujoco.mj_resetDataKeyframe(model, data, 0)
    mujoco.mj_kinematics(model, data)
    return model, data


def test_each_box_is_the_file_times_the_scale(compiled):
    from prsc.user_assets.asset_files import asset_at, describe_asset

    folder, _, objects = compiled
    for name, source, scale, joints in (("arm", DATA / "xarm/xarm6_robot.urdf", 0.5, {"joint3": -0.6}),
                                        ("lab", folder / "arm.xml", 2.0, {}), ("small", DATA / "table/table.urdf", 0.3, {})):
        # The box at the joint values the spec sets (joint3 of the arm), which the scale does not change.
        own = asset_at(describe_asset(source, [str(DATA)]), [str(DATA)], joints).size
        assert objects[name]["dimensions"] == pytest.approx([scale * v for v in own], rel=1e-6), name  # float32 mesh vertices
        assert objects[name]["properties"]["scale"] == scale


def test_every_length_and_mass_of_the_tree_scales_in_mujoco(compiled):
    import mujoco

    folder, root, objects = compiled
    model = mujoco.MjModel.from_xml_path(str(root / "mjcf" / "00000.xml"))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    for name, source, scale, base, tool in (("arm", DATA / "xarm/xarm6_robot.urdf", 0.5, "link_base", "link6"),
                                            ("lab", folder / "arm.xml", 2.0, "pedestal", "wrist")):
        alone, alone_data = _alone(source)
        mass = sum(model.body_mass[b] for b in range(model.nbody) if model.body(b).name.startswith(f"{name}/"))
        assert mass == pytest.approx(scale**3 * sum(alone.body_mass), rel=1e-6), name
        if name == "arm":  # the scene's joint3 differs from the file's home: compare at the same values
            alone_data.qpos[alone.joint("joint3").qposadr[0]] = -0.6
            mujoco.mj_kinematics(alone, alone_data)
        reach = np.linalg.norm(data.body(f"{name}/{tool}").xpos - data.body(f"{name}/{base}").xpos)
        own = np.linalg.norm(alone_data.body(tool).xpos - alone_data.body(base).xpos)
        assert reach == pytest.approx(scale * own, rel=1e-6), name
    # The scaled xArm holds its pose under the servos prsc gives it; the small table stands on the big one.
    joints = objects["arm"]["joints"]
    adr = {j: model.joint(f"arm/{j}").qposadr[0] for j in joints}
    small = model.body("small").id
    feet = min((data.geom_xpos[g] + model.mesh_vert[model.mesh_vertadr[model.geom_dataid[g]]:model.mesh_vertadr[model.geom_dataid[g]]
                                                    + model.mesh_vertnum[model.geom_dataid[g]]] @ data.geom_xmat[g].reshape(3, 3).T)[:, 2].min()
               for g in range(model.ngeom)
               if model.body_rootid[model.geom_bodyid[g]] == small and model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH)
    while data.time < 1.0:
        mujoco.mj_step(model, data)
    assert max(abs(data.qpos[adr[j]] - v) for j, v in joints.items()) < 0.02
    assert objects["small"]["static"]  # its root declares mass 0, as the unscaled file's does
    assert feet == pytest.approx(0.75, abs=1e-6)  # its legs (meshes, scaled) stand on the big table's top


def test_every_format_loads_the_scaled_files(compiled):
    import pybullet

    _, root, objects = compiled
    assert readback.usd_errors(root / "usd" / "00000.usda") == []
    folder = root / "urdf" / "00000"
    bundle = json.loads((folder / "scene.json").read_text())
    client = pybullet.connect(pybullet.DIRECT)
    try:
        entry = next(o for o in bundle["objects"] if o["name"] == "arm")
        body = pybullet.loadURDF(str(folder / entry["urdf"]), entry["base_position"], entry["base_orientation_xyzw"],
                                 useFixedBase=True, physicsClientId=client)
        low, high = pybullet.getAABB(body, -1, physicsClientId=client)
        assert pybullet.getNumJoints(body, physicsClientId=client) >= 6
        models = pybullet.loadSDF(str(root / "sdf" / "00000.sdf"), physicsClientId=client)
        assert len(models) >= 4
    finally:
        pybullet.disconnect(client)
    assert np.all(np.asarray(high) - np.asarray(low) < 0.2)  # the xArm's base link at half size (0.1 m)


@pytest.mark.parametrize("value, message", [
    ("(0.5, 1)", "must be a positive number, the same in every scene"),
    ("0", "must be a positive number"),
])
def test_a_random_or_nonpositive_scale_is_an_error_at_its_value(tmp_path, value, message):
    (tmp_path / "s.prs").write_text(textwrap.dedent(f"""\
        from tabletop import *
        class T:
            model: "table/table.urdf"
        t = T on Vector3D(0, 0, 0), with scale {value}
        """))
    done = _prsc("check", "s.prs", "-I", str(DATA), cwd=tmp_path)
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert done.stderr.startswith("s.prs:4:") and message in done.stderr, done.stderr
