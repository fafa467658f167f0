"""The converted Franka Panda: URDF and MJCF load in the real simulators and behave."""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET

import mujoco
import numpy as np
import pytest

from prsc.assets import panda


@pytest.fixture(scope="module")
def model() -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(panda.panda_mjcf_path()))


def _tcp_at(model: mujoco.MjModel, qpos_arm) -> np.ndarray:
    data = mujoco.MjData(model)
    data.qpos[:7] = qpos_arm
    mujoco.mj_kinematics(model, data)
    return data.site(panda.TCP_SITE).xpos.copy()


def test_mjcf_loads_from_any_cwd(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    model = mujoco.MjModel.from_xml_path(str(panda.panda_mjcf_path()))
    assert model.nmesh > 0 and model.nu == 8
    names = [model.actuator(i).name for i in range(model.nu)]
    assert names == [*panda.ARM_ACTUATORS, panda.GRIPPER_ACTUATOR]


def test_holds_home_pose_for_500_steps(model):
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    start = data.site(panda.TCP_SITE).xpos.copy()
    for _ in range(500):
        mujoco.mj_step(model, data)
    assert np.linalg.norm(data.site(panda.TCP_SITE).xpos - start) < 0.01


def test_actuators_drive_arm_and_gripper_to_targets(model):
    data = mujoco.MjData(model)
    start = np.array(panda.HOME_QPOS) + np.array([0.4, 0.3, -0.3, 0.4, 0.3, -0.3, 0.5])
    data.qpos[:7] = start
    data.ctrl[:7] = panda.HOME_QPOS
    data.ctrl[7] = panda.GRIPPER_CLOSED
    data.qpos[7:9] = panda.GRIPPER_OPEN
    for _ in range(1500):
        mujoco.mj_step(model, data)
    target = _tcp_at(model, panda.HOME_QPOS)
    assert np.linalg.norm(data.site(panda.TCP_SITE).xpos - target) < 0.01
    finger1, finger2 = (data.joint(j).qpos[0] for j in panda.FINGER_JOINTS)
    assert finger1 < 0.002 and abs(finger1 - finger2) < 0.002  # closed, mirrored


def test_arm_reaches_along_plus_y_of_base(model):
    tcp = _tcp_at(model, panda.HOME_QPOS)
    assert tcp[1] > 0.25 and abs(tcp[0]) < 1e-6
    assert model.body(panda.BASE_BODY).id == 1


def test_tcp_is_between_the_fingertips(model):
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    left = data.body("leftfinger").xpos
    right = data.body("rightfinger").xpos
    tcp = data.site(panda.TCP_SITE).xpos
    axis = data.site(panda.TCP_SITE).xmat.reshape(3, 3)[:, 2]  # approach direction
    mid = (left + right) / 2
    along = np.dot(tcp - mid, axis)
    assert 0.03 < along < 0.055  # within the finger pads, which are 5.4 cm long
    assert np.linalg.norm((tcp - mid) - along * axis) < 1e-6


def test_urdf_loads_in_pybullet():
    import pybullet

    client = pybullet.connect(pybullet.DIRECT)
    try:
        robot = pybullet.loadURDF(
            str(panda.panda_urdf_path()), useFixedBase=True,
            flags=pybullet.URDF_USE_INERTIA_FROM_FILE, physicsClientId=client,
        )
        names = [pybullet.getJointInfo(robot, i, physicsClientId=client)[1].decode()
                 for i in range(pybullet.getNumJoints(robot, physicsClientId=client))]
        assert set(panda.ARM_JOINTS + panda.FINGER_JOINTS) <= set(names)
        assert len(pybullet.getVisualShapeData(robot, physicsClientId=client)) > 0
        mass = pybullet.getDynamicsInfo(robot, names.index("joint1"), physicsClientId=client)[0]
        assert mass > 1.0
    finally:
        pybullet.disconnect(client)


def test_urdf_loads_in_yourdfpy_with_meshes():
    import yourdfpy

    robot = yourdfpy.URDF.load(str(panda.panda_urdf_path()), build_collision_scene_graph=True,
                               load_collision_meshes=True)
    assert len(robot.scene.geometry) > 0
    assert len(robot.collision_scene.geometry) > 0
    assert set(panda.ARM_JOINTS) <= set(robot.actuated_joint_names)


def test_inertias_are_real_and_positive_definite():
    root = ET.parse(panda.panda_urdf_path()).getroot()
    total = 0.0
    for link in root.findall("link"):
        inertial = link.find("inertial")
        assert inertial is not None, link.get("name")
        mass = float(inertial.find("mass").get("value"))
        i = {k: float(v) for k, v in inertial.find("inertia").attrib.items()}
        tensor = np.array([[i["ixx"], i["ixy"], i["ixz"]],
                           [i["ixy"], i["iyy"], i["iyz"]],
                           [i["ixz"], i["iyz"], i["izz"]]])
        assert not (i["ixx"] == i["iyy"] == i["izz"] == 0.1), link.get("name")
        eig = np.linalg.eigvalsh(tensor)
        assert mass > 0 and eig.min() > 0, link.get("name")
        # triangle inequality of principal moments: a physical rigid body
        assert eig[0] + eig[1] >= eig[2] * (1 - 1e-9), link.get("name")
        total += mass
    assert 17.0 < total < 19.0
    for mesh in root.iter("mesh"):
        assert os.path.isabs(mesh.get("filename")) and os.path.isfile(mesh.get("filename"))


def test_build_is_cached(tmp_path, monkeypatch):
    monkeypatch.setenv("PRSC_BUILD_DIR", str(tmp_path))
    first = (panda.panda_urdf_path(), panda.panda_mjcf_path())
    assert all(p.is_relative_to(tmp_path / "assets") for p in first)
    stamps = [(p.stat().st_ino, p.stat().st_mtime_ns) for p in first]
    second = (panda.panda_urdf_path(), panda.panda_mjcf_path())
    assert second == first
    assert [(p.stat().st_ino, p.stat().st_mtime_ns) for p in second] == stamps
    assert not [p for p in (tmp_path / "assets").rglob("*.tmp")]


@pytest.mark.filterwarnings("error")
def test_spec_attaches_with_prefix_and_saves(tmp_path):
    scene = mujoco.MjSpec()
    # The options the Panda spec carries (see its docstring): attaching warns on any difference.
    scene.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    scene.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    scene.option.impratio = 10.0
    mount = scene.worldbody.add_body(name="r1", pos=[0.3, -0.4, 0.8])
    frame = mount.add_frame()
    frame.attach_body(panda.panda_mjcf_spec().body(panda.BASE_BODY), "r1/", "")
    model = scene.compile()
    # The prefixed actuators drive the prefixed arm joint and the first finger (the second follows
    # by an equality), and the tool site is on the hand (a missing name is a KeyError; these check what the names hold).
    joint1 = model.actuator("r1/joint1").id
    assert model.actuator_trntype[joint1] == mujoco.mjtTrn.mjTRN_JOINT
    assert model.joint(model.actuator_trnid[joint1, 0]).name == "r1/joint1"
    gripper = model.actuator("r1/gripper").id
    assert model.actuator_trntype[gripper] == mujoco.mjtTrn.mjTRN_JOINT
    assert model.joint(model.actuator_trnid[gripper, 0]).name == "r1/finger_joint1"
    assert model.body(model.site("r1/tcp").bodyid[0]).name == "r1/hand"
    path = tmp_path / "scene.xml"
    path.write_text(scene.to_xml())
    reloaded = mujoco.MjModel.from_xml_path(str(path))
    assert reloaded.neq == 1 and reloaded.nu == 8
