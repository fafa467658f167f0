"""The library's Panda is a file arm: pybullet's Franka URDF read by the one asset path, plus the
gripper servo, `tcp` site, finger pads and home pose the library states as data
(prsc/library/panda.json). It loads, holds its pose, grips, and faces its object's +y."""

from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import mujoco
import numpy as np
import pybullet_data
import pytest

from prsc.assets.articulated import robot_model
from prsc.user_assets.asset_files import describe_asset, model_asset
from prsc.user_assets.asset_fitting import library_arm

FRANKA = Path(pybullet_data.getDataPath()) / "franka_panda"


@pytest.fixture(scope="module")
def arm():
    return library_arm("panda")


@pytest.fixture(scope="module")
def model() -> mujoco.MjModel:
    """The Panda as a scene attaches it, alone (prsc's servos on the arm, the library's gripper)."""
    return robot_model("panda").mjcf_spec().compile()


def _home(model: mujoco.MjModel) -> mujoco.MjData:
    data = mujoco.MjData(model)
    for name, value in robot_model("panda").home().items():
        data.joint(name).qpos[0] = value
    for a in range(model.nu):  # every servo at its joint's home
        data.ctrl[a] = data.qpos[model.jnt_qposadr[model.actuator_trnid[a, 0]]]
    mujoco.mj_forward(model, data)
    return data


def test_it_is_the_wheels_franka_urdf_read_as_any_urdf_is(arm):
    asset = model_asset("panda")
    assert Path(asset.source) == (FRANKA / "panda.urdf").resolve() and asset.format == "urdf"
    assert asset.fitting == arm.fitting and asset.tcp == "tcp"
    assert [j.name for j in asset.joints] == [f"panda_joint{i}" for i in range(1, 8)] + ["panda_finger_joint1",
                                                                                          "panda_finger_joint2"]
    # The fitting is part of the key: the same file read plainly is another asset.
    plain = describe_asset(asset.source)
    assert plain.digest != asset.digest and plain.tcp != "tcp" and "gripper" not in plain.actuators


def test_its_library_file_warns_nothing():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        describe_asset(FRANKA / "panda.urdf", (), library_arm("panda").fitting)


def test_the_library_adds_a_gripper_servo_and_the_second_finger_follows(model):
    names = [model.actuator(a).name for a in range(model.nu)]
    # prsc's servo on each arm joint (as on any URDF arm), the library's on the first finger; the
    # second finger follows it by the URDF's mimic and gets no servo of its own.
    assert sorted(names) == sorted(["gripper", *(f"panda_joint{i}" for i in range(1, 8))])
    data = _home(model)
    data.ctrl[model.actuator("gripper").id] = 0.0
    for _ in range(1500):
        mujoco.mj_step(model, data)
    first, second = data.joint("panda_finger_joint1").qpos[0], data.joint("panda_finger_joint2").qpos[0]
    assert first < 0.002 and abs(first - second) < 0.002  # closed, mirrored


def test_it_holds_home_and_faces_its_objects_plus_y(model):
    data = _home(model)
    start = data.site("tcp").xpos.copy()
    root = data.body(robot_model("panda").root).xpos
    assert start[1] - root[1] > 0.25 and abs(start[0] - root[0]) < 1e-3  # the hand ahead (+y) of the base
    for _ in range(500):
        mujoco.mj_step(model, data)
    assert np.linalg.norm(data.site("tcp").xpos - start) < 0.01
    assert data.site("tcp").xmat.reshape(3, 3)[2, 2] < -0.999  # the tool points down


def test_the_tcp_is_between_the_fingertips(model):
    data = _home(model)
    mid = (data.body("panda_leftfinger").xpos + data.body("panda_rightfinger").xpos) / 2
    tcp, axis = data.site("tcp").xpos, data.site("tcp").xmat.reshape(3, 3)[:, 2]
    along = np.dot(tcp - mid, axis)
    assert 0.03 < along < 0.055  # within the finger pads, which are 5.4 cm long
    assert np.linalg.norm((tcp - mid) - along * axis) < 1e-6


def test_its_key_and_urdf_entry_survive_pybullet_data_moving(tmp_path, arm):
    """Keyed by the content of every file it reads (asset_cache.py), not where the wheel sits."""
    copy = tmp_path / "elsewhere" / "franka_panda"
    shutil.copytree(FRANKA, copy)
    moved = describe_asset(copy / "panda.urdf", (), arm.fitting)
    assert moved.key == model_asset("panda").key
    urdf = robot_model("panda").urdf
    shutil.rmtree(copy)
    import pybullet

    client = pybullet.connect(pybullet.DIRECT)
    try:
        robot = pybullet.loadURDF(str(urdf), useFixedBase=True, physicsClientId=client)
        names = [pybullet.getJointInfo(robot, i, physicsClientId=client)[1].decode()
                 for i in range(pybullet.getNumJoints(robot, physicsClientId=client))]
        assert {f"panda_joint{i}" for i in range(1, 8)} <= set(names)
        assert len(pybullet.getVisualShapeData(robot, physicsClientId=client)) > 0
    finally:
        pybullet.disconnect(client)
