"""Every format of every hand-made scene loads in its real simulator with the scene's poses."""

from __future__ import annotations

import json
import math
import os
import shutil

import numpy as np
import pytest

from tests.backends import readback
from tests.backends.scenes import all_handmade

SCENES = sorted(all_handmade("unused.obj"))


def _files(handmade, name):
    scene, root = handmade[name]
    return scene, root


# ------------------------------------------------------------------ MJCF


@pytest.mark.parametrize("name", SCENES)
def test_mjcf_loads_with_exact_poses_and_settles(handmade, name):
    scene, root = _files(handmade, name)
    model = readback.mjcf_model(root / "mjcf" / "00000.xml")
    readback.assert_poses(readback.mjcf_poses(model, scene), scene, "mjcf")
    assert readback.mjcf_settle_failures(model) == []


def test_mjcf_loads_from_any_working_directory_and_after_a_move(handmade, tmp_path, monkeypatch):
    scene, root = _files(handmade, "table_cube")
    moved = tmp_path / "elsewhere"
    shutil.copytree(root, moved)
    monkeypatch.chdir("/")
    model = readback.mjcf_model(moved / "mjcf" / "00000.xml")
    assert model.nbody > len(scene["objects"])


def test_mjcf_follows_the_runner_naming(handmade):
    import mujoco

    scene, root = _files(handmade, "table_cube")
    model = readback.mjcf_model(root / "mjcf" / "00000.xml")
    # Each name holds what the runner drives through it (a missing name is a KeyError already).
    for robot in ("r1", "r2"):
        for name in [f"panda_joint{i}" for i in range(1, 8)]:  # the library Panda: the URDF's names
            actuator = model.actuator(f"{robot}/{name}").id
            assert model.actuator_trntype[actuator] == mujoco.mjtTrn.mjTRN_JOINT
            assert model.joint(model.actuator_trnid[actuator, 0]).name == f"{robot}/{name}"
        gripper = model.actuator(f"{robot}/gripper").id
        assert model.actuator_trntype[gripper] == mujoco.mjtTrn.mjTRN_JOINT
        assert model.joint(model.actuator_trnid[gripper, 0]).name == f"{robot}/panda_finger_joint1"
        assert model.body_parentid[model.body(f"{robot}/panda_link0").id] == model.body(robot).id
        assert model.body(model.site(f"{robot}/tcp").bodyid[0]).name == f"{robot}/panda_hand"
    assert model.body(model.camera("camera").bodyid[0]).name == "camera"
    for o in scene["objects"]:
        body = model.body(o["name"])
        has_free = any(model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE for j in range(body.jntadr[0], body.jntadr[0] + body.jntnum[0]))
        assert has_free == (not (o["static"] or o["camera"])), o["name"]
    # The robot box itself has no geom (it would collide with the arm).
    assert model.body("r1").geomnum[0] == 0
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    assert model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC


def test_mjcf_robot_root_sits_where_the_file_puts_it_reaching_along_y(handmade):
    import mujoco

    from prsc.assets.articulated import robot_model

    panda = robot_model("panda")
    scene, root = _files(handmade, "rotated_robot")
    model = readback.mjcf_model(root / "mjcf" / "00000.xml")
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    arm = next(o for o in scene["objects"] if o["name"] == "arm")
    rot = readback.quat_to_matrix(arm["quaternion"])
    bottom = np.asarray(arm["position"]) + rot @ np.asarray(panda.root_offset)  # no rootOffset: the file's at home
    assert np.allclose(data.xpos[model.body(f"arm/{panda.root}").id], bottom, atol=1e-6)
    # At home the tool centre is ahead of the base along the object's +y.
    tcp = data.site_xpos[model.site("arm/tcp").id] - bottom
    assert float(tcp @ rot[:, 1]) > 0.2 and abs(float(tcp @ rot[:, 0])) < 0.01


def test_mjcf_camera_looks_along_the_object_forward_axis(handmade):
    import mujoco

    scene, root = _files(handmade, "cube_in_air")
    model = readback.mjcf_model(root / "mjcf" / "00000.xml")
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    cam = next(o for o in scene["objects"] if o["name"] == "cam")
    rot = readback.quat_to_matrix(cam["quaternion"])
    xmat = data.cam_xmat[model.camera("cam").id].reshape(3, 3)
    assert np.allclose(-xmat[:, 2], rot[:, 1], atol=1e-9)  # looks along -Z = object +y
    assert np.allclose(xmat[:, 1], rot[:, 2], atol=1e-9)  # image up +Y = object +z
    assert model.cam_fovy[model.camera("cam").id] == pytest.approx(45.0)
    assert tuple(model.cam_resolution[model.camera("cam").id]) == (320, 240)


def test_mjcf_camera_sees_the_cube(handmade):
    """Render the camera's view: the blue cube it faces shows up near the image centre."""
    import mujoco

    scene, root = _files(handmade, "cube_in_air")
    model = readback.mjcf_model(root / "mjcf" / "00000.xml")
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    renderer = mujoco.Renderer(model, 240, 320)
    try:
        renderer.update_scene(data, camera="cam")
        image = renderer.render().astype(int)
    finally:
        renderer.close()
    blue = (image[:, :, 2] > 120) & (image[:, :, 0] < 80) & (image[:, :, 1] < 80)
    assert blue.sum() > 50
    rows, cols = np.nonzero(blue)
    assert abs(cols.mean() - 160) < 40 and abs(rows.mean() - 120) < 80


def test_mjcf_cube_drops_into_the_tray_and_stays_inside(handmade):
    import mujoco

    scene, root = _files(handmade, "tray_with_cube")
    model = readback.mjcf_model(root / "mjcf" / "00000.xml")
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    for _ in range(500):
        mujoco.mj_step(model, data)
    tray_floor_top = data.xpos[model.body("tray").id][2] - 0.028964 / 2 + 0.005792800000000001
    cube = data.xpos[model.body("cube").id]
    assert cube[2] == pytest.approx(tray_floor_top + 0.02, abs=1.5e-3)
    assert np.linalg.norm(cube[:2] - np.array([0.2, 0.1])) < 0.005


def test_mjcf_inertia_is_the_shape_inertia(handmade):
    scene, root = _files(handmade, "every_shape")
    model = readback.mjcf_model(root / "mjcf" / "00000.xml")
    box = next(o for o in scene["objects"] if o["name"] == "box_a")
    w, l, h = box["dimensions"]
    m = box["mass"]
    expected = sorted([m * (l * l + h * h) / 12, m * (w * w + h * h) / 12, m * (w * w + l * l) / 12])
    assert sorted(model.body_inertia[model.body("box_a").id]) == pytest.approx(expected, rel=1e-9)
    assert model.body_mass[model.body("box_a").id] == pytest.approx(m, rel=1e-12)
    sphere = next(o for o in scene["objects"] if o["name"] == "ball_a")
    r = min(sphere["dimensions"]) / 2
    assert model.body_inertia[model.body("ball_a").id] == pytest.approx([0.4 * sphere["mass"] * r * r] * 3, rel=1e-9)


# ------------------------------------------------------------------ URDF bundles


@pytest.mark.parametrize("name", SCENES)
def test_urdf_bundle_loads_in_pybullet_with_exact_poses_and_free_objects_fall(handmade, name):
    scene, root = _files(handmade, name)
    poses, drops = readback.urdf_bundle_load(root / "urdf" / "00000")
    readback.assert_poses(poses, scene, "urdf")
    readback.assert_free_fall(drops, scene)


@pytest.mark.parametrize("name", SCENES)
def test_urdf_bundle_validates_with_yourdfpy(handmade, name):
    _, root = _files(handmade, name)
    readback.urdf_validate(root / "urdf" / "00000")


def test_urdf_meshes_load_with_yourdfpy(handmade):
    import yourdfpy

    _, root = _files(handmade, "rotated_robot")
    robot = yourdfpy.URDF.load(str(root / "urdf" / "00000" / "arm.urdf"), load_meshes=True)
    assert len(robot.scene.geometry) > 10


def test_urdf_bundle_records_cameras(handmade):
    _, root = _files(handmade, "cube_in_air")
    bundle = json.loads((root / "urdf" / "00000" / "scene.json").read_text())
    cam = next(o for o in bundle["objects"] if o["name"] == "cam")
    assert cam["camera"] == {"fovy": 45.0, "resolution": [320, 240], "forward": [0.0, 1.0, 0.0], "up": [0.0, 0.0, 1.0]}


# ------------------------------------------------------------------ SDF


@pytest.mark.parametrize("name", SCENES)
def test_sdf_loads_in_pybullet_with_exact_poses(handmade, name):
    scene, root = _files(handmade, name)
    readback.assert_poses(readback.sdf_poses(root / "sdf" / "00000.sdf"), scene, "sdf")


@pytest.mark.skipif(shutil.which("ign") is None, reason="ign (Debian ignition-tools + libsdformat-dev) not installed")
@pytest.mark.parametrize("name", SCENES)
def test_sdf_passes_ign_sdf_check(handmade, name):
    _, root = _files(handmade, name)
    result = readback.ign_check(root / "sdf" / "00000.sdf")
    assert result.returncode == 0 and "Valid" in result.stdout, result.stderr[-2000:]


def test_sdf_robot_kinematics_match_the_urdf(handmade):
    """At the home posture every Panda link sits in the same place whether loaded from SDF or URDF."""
    import pybullet as p

    from prsc.assets.articulated import robot_model

    home = {j.name: j.home for j in robot_model("panda").joints if j.kind == "revolute"}
    _, root = _files(handmade, "rotated_robot")
    client = p.connect(p.DIRECT)
    try:
        bodies = p.loadSDF(str(root / "sdf" / "00000.sdf"), physicsClientId=client)
        from_sdf = next(b for b in bodies if p.getBodyInfo(b, physicsClientId=client)[1] == b"arm")
        bundle = json.loads((root / "urdf" / "00000" / "scene.json").read_text())
        entry = next(o for o in bundle["objects"] if o["name"] == "arm")
        from_urdf = p.loadURDF(str(root / "urdf" / "00000" / "arm.urdf"), entry["base_position"], entry["base_orientation_xyzw"],
                               useFixedBase=True, physicsClientId=client)

        def joints(body):
            return {p.getJointInfo(body, j, physicsClientId=client)[1].decode(): j for j in range(p.getNumJoints(body, physicsClientId=client))}

        js, ju = joints(from_sdf), joints(from_urdf)
        assert sorted(js) == sorted(ju)
        for name, q in home.items():
            p.resetJointState(from_sdf, js[name], q, physicsClientId=client)
            p.resetJointState(from_urdf, ju[name], q, physicsClientId=client)
        for name in js:
            a = p.getLinkState(from_sdf, js[name], computeForwardKinematics=True, physicsClientId=client)
            b = p.getLinkState(from_urdf, ju[name], computeForwardKinematics=True, physicsClientId=client)
            assert np.allclose(a[4], b[4], atol=1e-6) and np.allclose(np.abs(np.dot(a[5], b[5])), 1.0, atol=1e-9), name
    finally:
        p.disconnect(client)


# ------------------------------------------------------------------ USD


@pytest.mark.parametrize("name", SCENES)
def test_usd_validates_and_has_exact_poses(handmade, name):
    scene, root = _files(handmade, name)
    path = root / "usd" / "00000.usda"
    assert readback.usd_errors(path) == []
    readback.assert_poses(readback.usd_poses(path, scene), scene, "usd")


def test_usd_validator_is_not_vacuous(tmp_path):
    """The same validators flag a broken physics stage (negative mass, no stage metadata)."""
    from pxr import Usd, UsdGeom, UsdPhysics

    path = tmp_path / "bad.usda"
    stage = Usd.Stage.CreateNew(str(path))
    body = UsdGeom.Xform.Define(stage, "/World/body")
    UsdPhysics.RigidBodyAPI.Apply(body.GetPrim())
    UsdPhysics.MassAPI.Apply(body.GetPrim()).CreateMassAttr(-1.0)
    stage.GetRootLayer().Save()
    assert readback.usd_errors(path)


def test_usd_stage_has_physics_and_an_articulated_robot(handmade):
    from pxr import Usd, UsdGeom, UsdPhysics

    scene, root = _files(handmade, "table_cube")
    stage = Usd.Stage.Open(str(root / "usd" / "00000.usda"))
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z
    assert UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert UsdPhysics.GetStageKilogramsPerUnit(stage) == 1.0
    assert stage.GetDefaultPrim().GetPath() == "/World"
    assert any(p.IsA(UsdPhysics.Scene) for p in stage.Traverse())
    for o in scene["objects"]:
        prim = stage.GetPrimAtPath(f"/World/{o['name']}")
        if o["model"] in ("panda", "camera"):
            continue
        assert prim.HasAPI(UsdPhysics.RigidBodyAPI) and prim.HasAPI(UsdPhysics.MassAPI), o["name"]
        assert UsdPhysics.MassAPI(prim).GetMassAttr().Get() == pytest.approx(o["mass"], rel=1e-6)
        assert UsdPhysics.RigidBodyAPI(prim).GetKinematicEnabledAttr().Get() == o["static"]
        assert any(c.HasAPI(UsdPhysics.CollisionAPI) for c in prim.GetChildren()), o["name"]
    prim = _panda_prim()
    panda = stage.GetPrimAtPath(f"/World/r1/mount/{prim}")
    assert panda.HasAPI(UsdPhysics.ArticulationRootAPI)
    joint1 = UsdPhysics.RevoluteJoint(stage.GetPrimAtPath(f"/World/r1/mount/{prim}/joints/panda_joint1"))
    assert joint1.GetLowerLimitAttr().Get() == pytest.approx(math.degrees(-2.9671), rel=1e-6)
    finger = UsdPhysics.PrismaticJoint(stage.GetPrimAtPath(f"/World/r1/mount/{prim}/joints/panda_finger_joint1"))
    assert finger.GetUpperLimitAttr().Get() == pytest.approx(0.04)
    links = [p for p in panda.GetChildren() if p.HasAPI(UsdPhysics.RigidBodyAPI)]
    assert len(links) == 13 and all(any(c.HasAPI(UsdPhysics.CollisionAPI) for c in l.GetChildren())
                                    or l.GetName() in ("panda_link8", "panda_grasptarget") for l in links)


def _panda_prim() -> str:
    """The library Panda's USD prim: named after its asset key (the file's stem and content hash)."""
    from prsc.assets.articulated import robot_model

    return robot_model("panda").prim_name


def test_usd_robot_links_match_the_mjcf_at_home(handmade):
    """The USD articulation's link poses (home posture) equal MuJoCo's for the same scene."""
    import mujoco
    from pxr import Usd, UsdGeom

    scene, root = _files(handmade, "rotated_robot")
    model = readback.mjcf_model(root / "mjcf" / "00000.xml")
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    stage = Usd.Stage.Open(str(root / "usd" / "00000.usda"))
    cache = UsdGeom.XformCache()
    for link in ("panda_link0", "panda_link3", "panda_link7", "panda_hand", "panda_leftfinger"):
        m = cache.GetLocalToWorldTransform(stage.GetPrimAtPath(f"/World/arm/mount/{_panda_prim()}/{link}"))
        assert np.allclose([m[3][0], m[3][1], m[3][2]], data.xpos[model.body(f"arm/{link}").id], atol=2e-5), link


def test_usd_camera_looks_along_the_object_forward_axis(handmade):
    from pxr import Usd, UsdGeom

    scene, root = _files(handmade, "cube_in_air")
    stage = Usd.Stage.Open(str(root / "usd" / "00000.usda"))
    camera = UsdGeom.Camera(stage.GetPrimAtPath("/World/cam/camera"))
    m = UsdGeom.XformCache().GetLocalToWorldTransform(camera.GetPrim())
    rot = np.array([[m[i][j] for j in range(3)] for i in range(3)]).T  # columns: local axes
    cam = next(o for o in scene["objects"] if o["name"] == "cam")
    expected = readback.quat_to_matrix(cam["quaternion"])
    assert np.allclose(-rot[:, 2], expected[:, 1], atol=1e-9) and np.allclose(rot[:, 1], expected[:, 2], atol=1e-9)
    gf = camera.GetCamera()
    assert gf.GetFieldOfView(gf.FOVVertical) == pytest.approx(45.0, rel=1e-5)


# ------------------------------------------------------------------ JSON


@pytest.mark.parametrize("name", SCENES)
def test_json_target_writes_the_scene_itself(handmade, name):
    scene, root = _files(handmade, name)
    assert json.loads((root / "json" / "00000.json").read_text()) == scene


def test_relative_asset_paths_stay_inside_the_output_folder(handmade):
    _, root = _files(handmade, "every_shape")
    text = (root / "mjcf" / "00000.xml").read_text()
    assert str(root) not in text and "../assets/meshes/" in text
    assert not any(os.path.isabs(line) for line in text.split('"') if line.endswith(".obj"))


def test_a_free_floating_robot_is_free_in_every_format(tmp_path):
    """`static False` on a robot: a free body in MuJoCo and pybullet, no weld in USD."""
    from pxr import Usd

    from prsc.commands.compile import compile_scenes
    from tests.backends.scenes import rotated_robot

    scene = rotated_robot()
    scene["objects"][0]["static"] = False
    source = tmp_path / "free_robot.json"
    source.write_text(json.dumps(scene))
    root = compile_scenes(str(source), ["mjcf", "urdf", "sdf", "usd"], 1, 0, str(tmp_path / "out"))
    model = readback.mjcf_model(root / "mjcf" / "00000.xml")
    assert model.body_jntnum[model.body("arm").id] == 1 and model.body_subtreemass[model.body("arm").id] > 10
    _, drops = readback.urdf_bundle_load(root / "urdf" / "00000", visuals=False)
    readback.assert_free_fall(drops, scene)
    sdf = (root / "sdf" / "00000.sdf").read_text()
    assert "<static>0</static>" in sdf and "world_weld" not in sdf
    stage = Usd.Stage.Open(str(root / "usd" / "00000.usda"))
    weld = stage.GetPrimAtPath(f"/World/arm/mount/{_panda_prim()}/joints/root_joint")
    assert weld.GetAttribute("physics:jointEnabled").Get() is False
    assert readback.usd_errors(root / "usd" / "00000.usda") == []
