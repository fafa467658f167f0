"""A file's +x, the ROS forward, is its object's ahead (+y; LANGUAGE.md §7 "Forward"):
pybullet's Franka URDF at the back of a table, in a ready pose, holds its hand ahead of its
base, over the table, in MuJoCo, and the URDF bundle (pybullet), the SDF and the USD put the
hand where MuJoCo does. Before the turn its hand was 0.42 m to its side and 0.00 m ahead."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from tests.backends import readback

pybullet_data = pytest.importorskip("pybullet_data")
DATA = Path(pybullet_data.getDataPath())
READY = {"panda_joint1": 0.0, "panda_joint2": -0.785, "panda_joint3": 0.0, "panda_joint4": -2.356,
         "panda_joint5": 0.0, "panda_joint6": 1.571, "panda_joint7": 0.785}
"""The Franka's ready pose (rad): its hand in front of it, pointing down."""
HAND = "panda_hand"


@pytest.fixture(scope="module")
def franka(tmp_path_factory):
    folder = tmp_path_factory.mktemp("forward")
    joints = ", ".join(f'with joint "{name}" {value}' for name, value in READY.items())
    spec = folder / "franka.prs"
    spec.write_text(textwrap.dedent(f"""\
        from tabletop import *
        class Franka(Robot):
            model: "franka_panda/panda.urdf"
        table = Table on Vector3D(0, 0, 0), with width 1.8, with length 1.2, with height 0.75
        arm = Franka on (top back table).position + Vector3D(0, 0.25, 0), with tcp "panda_grasptarget", {joints}
        """))
    out = folder / "out"
    done = subprocess.run([sys.executable, "-m", "prsc.cli", "compile", str(spec), "-I", str(DATA), "-n", "1",
                           "--target", "json,mjcf,urdf,sdf,usd", "-o", str(out)],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    return out / "franka"


def _mujoco_hand(root: Path) -> tuple[np.ndarray, np.ndarray]:
    """The hand's and the base's world positions in the compiled MJCF at its `home` key."""
    import mujoco

    model = mujoco.MjModel.from_xml_path(str(root / "mjcf" / "00000.xml"))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    return data.body(f"arm/{HAND}").xpos.copy(), data.body("arm/panda_link0").xpos.copy()


def test_the_hand_is_ahead_of_the_base_over_the_table(franka):
    hand, base = _mujoco_hand(franka)
    ahead = hand - base
    assert ahead[1] > 0.3, f"the hand is {ahead[1]:.3f} m ahead of the base (+y), {ahead[0]:.3f} m to its side"
    assert abs(ahead[0]) < 0.02, f"the hand is {ahead[0]:.3f} m to the side of the base"
    # The box turned with the file: the arm's length (y) is its reach ahead, the base at its back.
    scene = json.loads((franka / "json" / "00000.json").read_text())
    arm = next(o for o in scene["objects"] if o["name"] == "arm")
    width, length = arm["dimensions"][:2]
    assert length > width
    assert arm["properties"]["rootOffset"][1] < 0


def test_every_format_puts_the_hand_where_mujoco_does(franka):
    hand, _ = _mujoco_hand(franka)
    # URDF bundle: pybullet at the bundle's pose and its stated joint values.
    import pybullet

    folder = franka / "urdf" / "00000"
    entry = next(o for o in json.loads((folder / "scene.json").read_text())["objects"] if o["name"] == "arm")
    client = pybullet.connect(pybullet.DIRECT)
    try:
        body = pybullet.loadURDF(str(folder / entry["urdf"]), entry["base_position"], entry["base_orientation_xyzw"],
                                 useFixedBase=True, physicsClientId=client)
        links = {}
        for j in range(pybullet.getNumJoints(body, physicsClientId=client)):
            info = pybullet.getJointInfo(body, j, physicsClientId=client)
            links[info[12].decode()] = j
            if info[1].decode() in entry["joints"]:
                pybullet.resetJointState(body, j, entry["joints"][info[1].decode()], physicsClientId=client)
        bullet = np.array(pybullet.getLinkState(body, links[HAND], computeForwardKinematics=True,
                                                physicsClientId=client)[4])
    finally:
        pybullet.disconnect(client)
    assert np.linalg.norm(bullet - hand) < 1e-4, f"URDF bundle: the hand {bullet} where MuJoCo has {hand}"
    # SDF: its links at the joint values it states.
    sdf = franka / "sdf" / "00000.sdf"
    stated = {j: v for (_, j), v in readback.sdf_joint_positions(sdf).items()}
    placed = readback.sdf_link_positions_at(sdf, "arm", stated)[HAND]
    assert np.linalg.norm(placed - hand) < 1e-4, f"SDF: the hand {placed} where MuJoCo has {hand}"
    # USD: the stage's own pose of the hand's prim.
    from pxr import Usd, UsdGeom

    stage, cache = Usd.Stage.Open(str(franka / "usd" / "00000.usda")), UsdGeom.XformCache()
    prims = [p for p in stage.Traverse() if p.GetName() == HAND and "/World/arm/" in str(p.GetPath())]
    assert prims, "USD: no prim for the hand"
    drawn = np.array(cache.GetLocalToWorldTransform(prims[0])).T[:3, 3]
    assert np.linalg.norm(drawn - hand) < 1e-4, f"USD: the hand {drawn} where MuJoCo has {hand}"
