"""The user's own arms (docs/assets.md): the xArm6 and KUKA iiwa URDFs that pybullet ships,
and a small actuated MJCF arm written here, compiled through the CLI to every format.

- MJCF: every joint arrives, the `home` key holds the scene's joint values, and over 1 s
  of simulation the arm holds them (servos, or gravity compensation where the file has no
  actuators) while the cubes around it stay put;
- the URDF bundle loads in pybullet with every joint, and its scene.json states where each
  starts; pybullet's SDF import loads the arm with its joints, and set at the joint values the
  SDF states, puts every link where MuJoCo's `home` key does; the USD validates and holds
  a revolute joint per arm joint under one articulation root, and Newton loads it with every
  joint at the scene's value;
- `reachable by` cubes are reached top-down by an IK solve on the compiled MuJoCo model
  (scipy's least squares, not prsc's own IK) within 5 mm and 0.05 rad.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from tests.backends import readback

pybullet_data = pytest.importorskip("pybullet_data")
DATA = Path(pybullet_data.getDataPath())
SCENES = 2
REACH_SCENES = 20

MJCF_ARM = """\
<mujoco model="lab_arm">
  <compiler angle="degree"/>
  <default><joint damping="2" armature="0.01"/><geom rgba="0.2 0.4 0.8 1"/></default>
  <worldbody>
    <body name="pedestal">
      <geom type="cylinder" size="0.06 0.05" pos="0 0 0.05"/>
      <body name="shoulder" pos="0 0 0.1">
        <joint name="yaw" axis="0 0 1" range="-170 170"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.04"/>
        <body name="upper" pos="0 0 0.2">
          <joint name="pitch" axis="0 1 0" range="-100 100"/>
          <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.035"/>
          <body name="fore" pos="0.3 0 0">
            <joint name="elbow" axis="0 1 0" range="-150 150"/>
            <geom type="capsule" fromto="0 0 0 0.25 0 0" size="0.03"/>
            <body name="wrist" pos="0.25 0 0" euler="0 90 0">
              <joint name="wrist" axis="0 1 0" range="-120 120"/>
              <geom type="box" size="0.03 0.03 0.03"/>
              <site name="tcp" pos="0 0 0.05"/>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position name="yaw" joint="yaw" kp="2000" kv="100"/>
    <position name="pitch" joint="pitch" kp="4000" kv="200"/>
    <position name="elbow" joint="elbow" kp="3000" kv="150"/>
    <position name="wrist" joint="wrist" kp="1000" kv="50"/>
  </actuator>
  <keyframe><key name="home" qpos="0 -0.5 1.2 0.9"/></keyframe>
</mujoco>
"""

ARMS = {
    "xarm6": ("xarm/xarm6_robot.urdf", 6, 'with joint "joint2" (-0.3, 0.3), with joint "joint3" -0.6'),
    "kuka_iiwa": ("kuka_iiwa/model.urdf", 7, 'with joint "lbr_iiwa_joint_4" 0.5 deg'),
    "lab_arm": ("arm.xml", 4, 'with joint "yaw" (-0.5, 0.5)'),
}


REACHABLE_CUBES = "".join(f"c{k} = Cube completely on table, reachable by arm\n" for k in (1, 2, 3))


def _spec(folder: Path, model: str, joints: str, objects: str = REACHABLE_CUBES) -> Path:
    """An arm at the back of a table (`joints`: its specifiers), and `objects` after it."""
    spec = folder / "arm.prs"
    spec.write_text(textwrap.dedent(f"""\
        from tabletop import *
        table = Table on Vector3D(0, 0, 0), with width 1.8, with length 1.2, with height 0.75
        class Arm(Robot):
            model: "{model}"
        arm = Arm on (top back table).position + Vector3D(0, 0.25, 0), {joints}
        """) + objects)
    return spec


def _prsc(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "prsc.cli", *args], capture_output=True, text=True, timeout=600)


# The KUKA runs the same checks from test_user_arm_kuka.py: a file of its own, so that the
# suite's two workers (--dist loadfile) share the arms' reach builds (3-7 s of CPU each).
HERE = ("lab_arm", "xarm6")


@pytest.fixture(scope="module", params=HERE)
def arm_output(request, tmp_path_factory):
    return compiled_arm(request.param, tmp_path_factory)


def compiled_arm(name: str, tmp_path_factory) -> tuple:
    """The arm's spec compiled to every format: (name, its `with joint` text, output folder, scenes)."""
    folder = tmp_path_factory.mktemp(name)
    if name == "lab_arm":
        (folder / "arm.xml").write_text(MJCF_ARM)
    model, joints, setting = ARMS[name]
    spec = _spec(folder, model, setting)
    out = folder / "out"
    done = _prsc("compile", str(spec), "-I", str(DATA), "-n", str(SCENES), "--target", "json,mjcf,urdf,sdf,usd",
                 "-o", str(out))
    assert done.returncode == 0, done.stderr
    root = out / "arm"
    scenes = [json.loads((root / "json" / f"{k:05d}.json").read_text()) for k in range(SCENES)]
    return name, joints, root, scenes


def _arm(scene: dict) -> dict:
    return next(o for o in scene["objects"] if o["name"] == "arm")


def test_mjcf_has_every_joint_and_holds_the_scene_joint_values(arm_output):
    import mujoco

    name, joints, root, scenes = arm_output
    for k, scene in enumerate(scenes):
        model = mujoco.MjModel.from_xml_path(str(root / "mjcf" / f"{k:05d}.xml"))
        data = mujoco.MjData(model)
        arm_joints = [model.joint(j).name for j in range(model.njnt) if model.joint(j).name.startswith("arm/")]
        assert len(arm_joints) == joints
        mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
        wanted = _arm(scene)["joints"]
        assert sorted(wanted) == sorted(j[len("arm/"):] for j in arm_joints)
        adr = {j: model.jnt_qposadr[model.joint(f"arm/{j}").id] for j in wanted}
        assert all(abs(data.qpos[adr[j]] - v) < 1e-9 for j, v in wanted.items())
        mujoco.mj_forward(model, data)
        cubes = {o["name"]: data.body(o["name"]).xpos.copy() for o in scene["objects"] if o["name"].startswith("c")}
        while data.time < 1.0:
            mujoco.mj_step(model, data)
        drift = max(abs(data.qpos[adr[j]] - v) for j, v in wanted.items())
        assert drift < 0.02, f"{name} scene {k}: the arm left its home pose by {drift:.3f} rad"
        moved = max(np.linalg.norm(data.body(c).xpos - p) for c, p in cubes.items())
        assert moved < 1e-3, f"{name} scene {k}: a cube moved {moved * 1000:.1f} mm"


def test_urdf_bundle_sdf_and_usd_carry_every_joint(arm_output):
    import pybullet

    from pxr import Usd, UsdPhysics

    name, joints, root, scenes = arm_output
    folder = root / "urdf" / "00000"
    bundle = json.loads((folder / "scene.json").read_text())
    entry = next(o for o in bundle["objects"] if o["name"] == "arm")
    assert entry["joints"] == _arm(scenes[0])["joints"]
    client = pybullet.connect(pybullet.DIRECT)
    try:
        body = pybullet.loadURDF(str(folder / entry["urdf"]), entry["base_position"], entry["base_orientation_xyzw"],
                                 useFixedBase=True, physicsClientId=client)
        movable = [pybullet.getJointInfo(body, j, physicsClientId=client)[1].decode()
                   for j in range(pybullet.getNumJoints(body, physicsClientId=client))
                   if pybullet.getJointInfo(body, j, physicsClientId=client)[2] != pybullet.JOINT_FIXED]
        assert sorted(movable) == sorted(entry["joints"])
        models = pybullet.loadSDF(str(root / "sdf" / "00000.sdf"), physicsClientId=client)
        counts = [sum(pybullet.getJointInfo(m, j, physicsClientId=client)[2] != pybullet.JOINT_FIXED
                      for j in range(pybullet.getNumJoints(m, physicsClientId=client))) for m in models]
        assert joints in counts
    finally:
        pybullet.disconnect(client)
    readback.urdf_validate(folder)
    usd = root / "usd" / "00000.usda"
    assert readback.usd_errors(usd) == []
    stage = Usd.Stage.Open(str(usd))
    revolute = [p for p in stage.Traverse() if p.IsA(UsdPhysics.RevoluteJoint) and "/arm/" in str(p.GetPath())]
    assert len(revolute) == joints
    assert any(p.HasAPI(UsdPhysics.ArticulationRootAPI) and "/arm/" in str(p.GetPath()) for p in stage.Traverse())
    # Each drive holds its joint at the scene's value (degrees), not at the file's home.
    values = _arm(scenes[0])["joints"]
    driven = [p for p in revolute if p.GetName() in values and p.HasAPI(UsdPhysics.DriveAPI, "angular")]
    assert len(driven) == joints
    for prim in driven:
        target = UsdPhysics.DriveAPI(prim, "angular").GetTargetPositionAttr().Get()
        assert target == pytest.approx(np.degrees(values[prim.GetName()]), abs=1e-4)


def test_the_sdf_states_where_every_joint_starts_and_pybullet_set_there_matches_mujoco(arm_output):
    import mujoco

    name, joints, root, scenes = arm_output
    k = len(scenes) - 1
    sdf = root / "sdf" / f"{k:05d}.sdf"
    wanted = _arm(scenes[k])["joints"]
    stated = readback.sdf_joint_positions(sdf)
    assert stated == {("arm", j): pytest.approx(v, abs=1e-12) for j, v in wanted.items()}
    links = readback.sdf_link_positions_at(sdf, "arm", {j: v for (_, j), v in stated.items()})
    model = mujoco.MjModel.from_xml_path(str(root / "mjcf" / f"{k:05d}.xml"))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    both = [link for link in links if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"arm/{link}") >= 0]
    assert len(both) >= joints, f"{name}: only {both} are links in both"
    gap = max(np.linalg.norm(links[link] - data.body(f"arm/{link}").xpos) for link in both)
    assert gap < 1e-5, f"{name}: pybullet at the SDF's joint values puts a link {gap * 1000:.2f} mm from MuJoCo's home"


def test_newton_loads_the_usd_with_every_joint_where_the_scene_starts_it(arm_output):
    name, joints, root, scenes = arm_output
    for k, scene in enumerate(scenes):
        loaded = readback.newton_load(root / "usd" / f"{k:05d}.usda")
        wanted = _arm(scene)["joints"]
        assert len(wanted) == joints
        assert {j: loaded["joints"].get(j) for j in wanted} == pytest.approx(wanted, abs=1e-6), f"{name} scene {k}"
        # Newton's forward kinematics from those values puts every link where the stage draws it.
        assert loaded["fk_gap"] < 1e-5, f"{name} scene {k}: a body {loaded['fk_gap']:.2e} m off"
        assert "table" in loaded["kinematic"] and {"c1", "c2", "c3"} <= loaded["free"]


def _top_down_ik(model, data, tool, is_site: bool, qadr: np.ndarray, target: np.ndarray, start: np.ndarray,
                 base: np.ndarray | None = None):
    """Joint values putting the tool at `target` with its +z down (scipy least squares), from
    `start`, from it bent either way and, given the arm's `base`, from it with the first
    joint turned by the target's azimuth less the tool's at `start` (a local solve from home
    does not swing the base round to a point behind the arm)."""
    import mujoco
    from scipy.optimize import least_squares

    lower, upper = model.jnt_range[qadr_joint(model, qadr)].T
    seeds = [start, start + 0.4, start - 0.4]
    if base is not None:
        data.qpos[qadr] = start
        mujoco.mj_kinematics(model, data)
        tool_at = (data.site_xpos[tool] if is_site else data.xpos[tool]) - base
        turn = math.atan2(*(target - base)[1::-1]) - math.atan2(*tool_at[1::-1])
        turned = start.copy()
        turned[0] += (turn + math.pi) % (2 * math.pi) - math.pi
        seeds += [turned, turned + 0.4, turned - 0.4]

    def residual(q):
        data.qpos[qadr] = q
        mujoco.mj_kinematics(model, data)
        position = data.site_xpos[tool] if is_site else data.xpos[tool]
        rotation = (data.site_xmat[tool] if is_site else data.xmat[tool]).reshape(3, 3)
        return np.concatenate([position - target, 0.2 * (rotation[:, 2] + np.array([0.0, 0.0, 1.0]))])

    best = None
    for seed in seeds:
        fit = least_squares(residual, np.clip(seed, lower + 1e-6, upper - 1e-6), bounds=(lower, upper), xtol=1e-12,
                            ftol=1e-12, gtol=1e-12)
        if best is None or fit.cost < best.cost:
            best = fit
        if best.cost < 1e-10:
            break
    return best.x


def qadr_joint(model, qadr: np.ndarray) -> np.ndarray:
    return np.array([int(np.flatnonzero(model.jnt_qposadr == a)[0]) for a in qadr])


def _cubes_reached_top_down(root: Path, scenes: int, name: str) -> float:
    """Assert that in every scene the arm's tool (the scene's `tcp`) reaches every cube
    top-down on the compiled model (scipy's IK); the farthest cube's distance from the base."""
    import mujoco

    from prsc.user_assets.asset_files import describe_asset

    farthest = 0.0
    for k in range(scenes):
        scene = json.loads((root / "json" / f"{k:05d}.json").read_text())
        asset = describe_asset(_arm(scene)["model"])
        tcp = _arm(scene)["properties"]["tcp"]
        model = mujoco.MjModel.from_xml_path(str(root / "mjcf" / f"{k:05d}.xml"))
        data = mujoco.MjData(model)
        mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
        is_site = tcp in asset.sites
        tool = (model.site if is_site else model.body)(f"arm/{tcp}").id
        qadr = np.array([model.jnt_qposadr[model.joint(f"arm/{j.name}").id] for j in asset.joints])
        mujoco.mj_kinematics(model, data)  # the base where the scene puts it (xpos is zero after a reset)
        base = data.body(f"arm/{asset.root}").xpos.copy()
        for cube in (o for o in scene["objects"] if o["name"].startswith("c")):
            target = np.array(cube["position"])
            q = _top_down_ik(model, data, tool, is_site, qadr, target, np.array([j.home for j in asset.joints]), base)
            data.qpos[qadr] = q
            mujoco.mj_kinematics(model, data)
            position = data.site_xpos[tool] if is_site else data.xpos[tool]
            axis = (data.site_xmat[tool] if is_site else data.xmat[tool]).reshape(3, 3)[:, 2]
            error, angle = np.linalg.norm(position - target), np.arccos(min(1.0, -axis[2]))
            assert error < 0.005 and angle < 0.05, f"{name} scene {k} {cube['name']}: {error * 1000:.1f} mm, {angle:.3f} rad"
            farthest = max(farthest, float(np.linalg.norm((target - base)[:2])))
    return farthest


def test_reachable_cubes_are_reached_top_down_on_the_compiled_model(arm_output, tmp_path):
    name, joints, root, _ = arm_output
    spec = root.parent.parent / "arm.prs"
    out = tmp_path / "reach"
    done = _prsc("compile", str(spec), "-I", str(DATA), "-n", str(REACH_SCENES), "--target", "json,mjcf", "-o", str(out))
    assert done.returncode == 0, done.stderr
    farthest = _cubes_reached_top_down(out / "arm", REACH_SCENES, name)
    if name == "xarm6":
        assert farthest >= 0.45, f"the farthest reachable cube is {farthest:.3f} m from the xArm's base"


def test_the_reach_check_fails_on_a_cube_out_of_reach(arm_output):
    """The IK above is not vacuous: a point 2 m from the base is not reached."""
    import mujoco

    from prsc.user_assets.asset_files import describe_asset

    name, joints, root, scenes = arm_output
    asset = describe_asset(_arm(scenes[0])["model"])
    model = mujoco.MjModel.from_xml_path(str(root / "mjcf" / "00000.xml"))
    data = mujoco.MjData(model)
    is_site = asset.tcp in asset.sites
    tool = (model.site if is_site else model.body)(f"arm/{asset.tcp}").id
    qadr = np.array([model.jnt_qposadr[model.joint(f"arm/{j.name}").id] for j in asset.joints])
    mujoco.mj_kinematics(model, data)
    target = data.body(f"arm/{asset.root}").xpos + np.array([2.0, 0.0, 0.0])
    q = _top_down_ik(model, data, tool, is_site, qadr, target, np.array([j.home for j in asset.joints]))
    data.qpos[qadr] = q
    mujoco.mj_kinematics(model, data)
    position = data.site_xpos[tool] if is_site else data.xpos[tool]
    assert np.linalg.norm(position - target) > 0.5


def test_the_example_spec_compiles_as_its_docstring_says(tmp_path):
    spec = Path(__file__).resolve().parents[2] / "specs" / "pybullet_arm" / "xarm_cubes.prs"
    done = _prsc("compile", str(spec), "--target", "json,mjcf", "-n", "2", "-I", str(DATA), "-o", str(tmp_path))
    assert done.returncode == 0, done.stderr
    scene = json.loads((tmp_path / "xarm_cubes" / "json" / "00001.json").read_text())
    assert len(_arm(scene)["joints"]) == 6


def test_the_example_controller_drives_every_arm_by_its_own_names(arm_output, tmp_path):
    """`prsc run --controller prsc.runner.visit:visit` (no Panda constants): the
    tool visits a point above each reachable cube, under the arm's own servos (a URDF arm's
    from prsc), in every episode."""
    name, _, root, _ = arm_output
    spec = root.parent.parent / "arm.prs"
    done = _prsc("run", str(spec), "-I", str(DATA), "--controller", "prsc.runner.visit:visit", "-n", "3",
                 "-o", str(tmp_path / "run"))
    assert done.returncode == 0, done.stderr
    records = [json.loads(line) for line in (tmp_path / "run" / "results.jsonl").read_text().splitlines()]
    assert [r["outcome"] for r in records] == ["visited"] * 3, records
    assert max(r["worst"] for r in records) < 0.01


def test_a_spec_tcp_has_its_own_reach_and_the_controller_drives_it(tmp_path):
    """`with tcp "wrist"` (the wrist body, 5 cm behind the file's `tcp` site): `reachable by`
    is built for that frame, cached apart from the site's, and the cubes are reached
    top-down by the wrist; the example controller `visit` drives the wrist."""
    import mujoco

    from prsc.user_assets.asset_files import build_root, describe_asset

    (tmp_path / "arm.xml").write_text(MJCF_ARM)
    spec = _spec(tmp_path, "arm.xml", 'with tcp "wrist"')
    out = tmp_path / "out"
    done = _prsc("compile", str(spec), "-n", str(REACH_SCENES), "--target", "json,mjcf", "-o", str(out))
    assert done.returncode == 0, done.stderr
    stem = describe_asset(str(tmp_path / "arm.xml")).key
    tools = sorted(p.name[len(stem) + 1:].split("-")[0] for p in (build_root() / "reach").glob(f"{stem}-*.json"))
    assert "wrist" in tools, tools  # built for the wrist (the site's own reach may be there from the other tests)
    for k in range(REACH_SCENES):
        assert _arm(json.loads((out / "arm" / "json" / f"{k:05d}.json").read_text()))["properties"]["tcp"] == "wrist"
    _cubes_reached_top_down(out / "arm", REACH_SCENES, "lab_arm with tcp wrist")
    # The example controller drives the same frame: after its run, the wrist (not the site
    # 5 cm beyond it) stands at the point above the last cube.
    from prsc.runner.visit import HOVER, visit

    scene = json.loads((out / "arm" / "json" / "00000.json").read_text())
    model = mujoco.MjModel.from_xml_path(str(out / "arm" / "mjcf" / "00000.xml"))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    record = visit(scene, model, data)
    assert record["outcome"] == "visited", record
    last = [o for o in scene["objects"] if o["name"].startswith("c")][-1]
    point = np.array(last["position"]) + [0.0, 0.0, HOVER]
    assert np.linalg.norm(data.body("arm/wrist").xpos - point) < 0.01
    assert np.linalg.norm(data.site("arm/tcp").xpos - point) > 0.04


def test_an_arm_of_torque_motors_holds_its_pose_and_controllers_get_position_servos(tmp_path):
    """robosuite's arms drive their joints with torque `<motor>`s, which hold nothing at 0: the arm
    keeps them, and gets gravity compensation and prsc's position servos, which the runner drives."""
    import mujoco

    from prsc.user_assets.arm_ik import ArmFrames
    from prsc.runner.arm_scene import SceneArm, servos

    motors = MJCF_ARM.split("<actuator>")[0] + "<actuator>\n" + "".join(
        f'    <motor name="{j}" joint="{j}" gear="1" ctrlrange="-50 50"/>\n' for j in ("yaw", "pitch", "elbow", "wrist")
    ) + "  </actuator>" + MJCF_ARM.split("</actuator>")[1]
    (tmp_path / "arm.xml").write_text(motors)
    spec = _spec(tmp_path, "arm.xml", 'with joint "elbow" 1.0', objects="c1 = Cube completely on table\n")
    done = _prsc("compile", str(spec), "-n", "1", "--target", "json,mjcf", "-o", str(tmp_path / "out"))
    assert done.returncode == 0, done.stderr
    root = tmp_path / "out" / "arm"
    scene = json.loads((root / "json" / "00000.json").read_text())
    model = mujoco.MjModel.from_xml_path(str(root / "mjcf" / "00000.xml"))
    data = mujoco.MjData(model)
    assert {model.actuator(a).name for a in range(model.nu)} >= {"arm/yaw", "arm/yaw_servo", "arm/wrist_servo"}
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    wanted = _arm(scene)["joints"]
    adr = {j: model.jnt_qposadr[model.joint(f"arm/{j}").id] for j in wanted}
    while data.time < 1.0:
        mujoco.mj_step(model, data)
    drift = max(abs(data.qpos[adr[j]] - v) for j, v in wanted.items())
    assert drift < 0.02, f"the arm of motors left its home pose by {drift:.3f} rad"
    # The runner drives the servos, not the motors: a position sent moves the joint there.
    frames = SceneArm.of(scene, model, "test").frames
    assert isinstance(frames, ArmFrames)
    drive = servos(model, frames)
    assert all(model.actuator(a).name.endswith("_servo") for a in drive)
    data.ctrl[drive] = data.qpos[frames.qpos] + 0.2
    mujoco.mj_step(model, data, nstep=int(2.0 / model.opt.timestep))
    assert np.allclose(data.qpos[frames.qpos], data.ctrl[drive], atol=0.02)


def test_a_tool_that_cannot_point_down_is_an_error_that_names_the_other_frames(tmp_path):
    (tmp_path / "arm.xml").write_text(MJCF_ARM)
    spec = _spec(tmp_path, "arm.xml", 'with tcp "shoulder"')
    done = _prsc("check", str(spec))
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "reaches no sector" in done.stderr and 'with tcp "NAME"' in done.stderr and "'tcp'" in done.stderr, done.stderr


def _geometry_box(model, data, prefix: str) -> tuple[np.ndarray, np.ndarray]:
    """The world box of every geom of the bodies named `prefix...` (mesh vertices, else MuJoCo's boxes)."""
    import mujoco

    points = []
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    for g in range(model.ngeom):
        if not model.body(model.geom_bodyid[g]).name.startswith(prefix):
            continue
        if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH:
            mesh = model.geom_dataid[g]
            local = model.mesh_vert[model.mesh_vertadr[mesh]:model.mesh_vertadr[mesh] + model.mesh_vertnum[mesh]]
        else:
            local = model.geom_aabb[g, :3] + corners * model.geom_aabb[g, 3:]
        points.append(data.geom_xpos[g] + local @ data.geom_xmat[g].reshape(3, 3).T)
    stacked = np.concatenate(points)
    return stacked.min(axis=0), stacked.max(axis=0)


@pytest.mark.parametrize("joints", ['with joint "pitch" 1.2, with joint "elbow" 0.3', 'with joint "pitch" -1.0'])
def test_the_box_is_the_files_at_the_joint_values_the_spec_sets(tmp_path, joints):
    """LANGUAGE.md section 7: the box at the initial joint values. Pitched down, the arm reaches below
    its root; its box goes down with it and stands on the table, so nothing enters the table."""
    import mujoco

    (tmp_path / "arm.xml").write_text(MJCF_ARM)
    spec = _spec(tmp_path, "arm.xml", joints, objects="")
    done = _prsc("compile", str(spec), "-n", "1", "--target", "json,mjcf", "-o", str(tmp_path / "out"))
    assert done.returncode == 0, done.stderr
    root = tmp_path / "out" / "arm"
    arm = _arm(json.loads((root / "json" / "00000.json").read_text()))
    model = mujoco.MjModel.from_xml_path(str(root / "mjcf" / "00000.xml"))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_kinematics(model, data)
    low, high = _geometry_box(model, data, "arm/")
    centre, half = np.asarray(arm["position"]), np.asarray(arm["dimensions"]) / 2
    assert np.allclose(low, centre - half, atol=1e-6) and np.allclose(high, centre + half, atol=1e-6)
    assert low[2] == pytest.approx(0.75, abs=1e-6)  # on the table's top, not in it, not above it


FOLDED_ARM = """\
<mujoco model="folded">
  <compiler angle="radian"/>
  <worldbody>
    <body name="pedestal">
      <geom type="box" size="0.08 0.08 0.05" pos="0 0 0.05"/>
      <body name="upper" pos="0 0 0.1">
        <joint name="shoulder" axis="0 1 0" range="-2 2"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.3" size="0.03"/>
        <body name="fore" pos="0 0 0.3">
          <joint name="elbow" axis="0 1 0" range="-3 3"/>
          <geom type="capsule" fromto="0 0 0 0 0 -0.29" size="0.03"/>
          <site name="tcp" pos="0 0 -0.29"/>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position name="shoulder" joint="shoulder" kp="400" kv="40"/>
    <position name="elbow" joint="elbow" kp="200" kv="20"/>
  </actuator>
  <keyframe><key name="home" qpos="0.0 0.0"/></keyframe>
</mujoco>
"""


def test_links_that_touch_at_home_do_not_push_each_other_away(tmp_path):
    """The forearm folded down along the upper arm reaches into the pedestal, its grandparent (as
    dm_control's Jaco folds link 4 onto link 2): that pair does not collide, so the arm holds home."""
    import mujoco

    (tmp_path / "arm.xml").write_text(FOLDED_ARM)
    spec = _spec(tmp_path, "arm.xml", "with joint \"elbow\" 0.0", objects="")
    done = _prsc("compile", str(spec), "-n", "1", "--target", "json,mjcf", "-o", str(tmp_path / "out"))
    assert done.returncode == 0, done.stderr
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "out" / "arm" / "mjcf" / "00000.xml"))
    data = mujoco.MjData(model)
    pairs = {tuple(sorted(model.body(b).name for b in (model.exclude_signature[k] >> 16, model.exclude_signature[k] & 0xFFFF)))
             for k in range(model.nexclude)}
    assert ("arm/fore", "arm/pedestal") in pairs
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    while data.time < 1.0:
        mujoco.mj_step(model, data)
    assert np.abs(data.qpos[[model.joint("arm/shoulder").qposadr[0], model.joint("arm/elbow").qposadr[0]]]).max() < 0.02
