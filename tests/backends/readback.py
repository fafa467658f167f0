"""Load each output format in its real simulator or library and read the scene back."""

from __future__ import annotations

import json
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from prsc.geometry.rotations import quat_to_matrix

POSE_TOL = 1e-6


def pose_error(position, quaternion, expected: dict) -> tuple[float, float]:
    """(position error, rotation-matrix error) against a scene object."""
    dp = float(np.max(np.abs(np.asarray(position, float) - np.asarray(expected["position"], float))))
    dr = float(np.max(np.abs(quat_to_matrix(quaternion) - quat_to_matrix(expected["quaternion"]))))
    return dp, dr


def assert_poses(poses: dict[str, tuple], scene: dict, fmt: str) -> None:
    """Every object's pose read back equals the scene JSON's to POSE_TOL."""
    for o in scene["objects"]:
        assert o["name"] in poses, f"{fmt}: object {o['name']} missing"
        dp, dr = pose_error(*poses[o["name"]], o)
        assert dp <= POSE_TOL and dr <= POSE_TOL, f"{fmt}: {o['name']} pose off by {dp:.2e} m / {dr:.2e}"


# ------------------------------------------------------------------ MJCF


def mjcf_model(path: Path):
    import mujoco

    return mujoco.MjModel.from_xml_path(str(path))


def scene_at_home(root: Path, k: int):
    """(scene JSON, MjModel, MjData) of scene k of a compiled folder, at its `home` key."""
    import mujoco

    scene = json.loads((root / "json" / f"{k:05d}.json").read_text())
    model = mujoco.MjModel.from_xml_path(str(root / "mjcf" / f"{k:05d}.xml"))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    return scene, model, data


def mjcf_poses(model, scene: dict) -> dict[str, tuple]:
    """World pose of every object body after mj_forward at the home keyframe."""
    import mujoco

    data = mujoco.MjData(model)
    if model.nkey:
        mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    out = {}
    for o in scene["objects"]:
        body = model.body(o["name"])
        out[o["name"]] = (data.xpos[body.id].copy(), data.xquat[body.id].copy())
    return out


def mjcf_settle_failures(model, steps: int = 200, moved: float = 0.005, penetration: float = 0.001) -> list[str]:
    """Free bodies that start interpenetrating, or move other than by falling onto a support.

    A body may stay put (it moved at most `moved`) or fall: drop by more than `moved`
    while shifting sideways by no more than its bounding diameter (a block on a tray's rim
    plane that overlaps a wall tips over the wall's inner edge onto the floor: its centre
    ends within a radius of that edge, which is within a radius of where it started).
    Rising, or sliding without falling, is a failure.
    """
    import mujoco

    data = mujoco.MjData(model)
    if model.nkey:
        mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    free = [j for j in range(model.njnt) if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE]
    free_bodies = {int(model.jnt_bodyid[j]) for j in free}
    failures = []
    for c in data.contact[: data.ncon]:
        bodies = {int(model.geom_bodyid[c.geom[0]]), int(model.geom_bodyid[c.geom[1]])}
        roots = {int(model.body_rootid[b]) for b in bodies}
        if c.dist < -penetration and (roots & free_bodies):
            names = sorted(model.body(b).name for b in bodies)
            failures.append(f"initial interpenetration {c.dist * 1000:.2f} mm between {names}")
    start = {b: data.xpos[b].copy() for b in free_bodies}
    for _ in range(steps):
        mujoco.mj_step(model, data)
    for j in free:
        b = int(model.jnt_bodyid[j])
        d = data.xpos[b] - start[b]
        geoms = range(model.body_geomadr[b], model.body_geomadr[b] + model.body_geomnum[b])
        radius = max((float(np.linalg.norm(model.geom_pos[g]) + model.geom_rbound[g]) for g in geoms), default=0.0)
        sideways = float(np.hypot(d[0], d[1]))
        stayed = float(np.linalg.norm(d)) <= moved
        fell = d[2] < -moved and sideways <= 2 * radius
        if not (stayed or fell):
            failures.append(f"{model.body(b).name} moved {np.round(d * 1000, 2).tolist()} mm")
    return failures


# ------------------------------------------------------------------ pybullet (URDF bundles and SDF)


def _bullet():
    import pybullet

    return pybullet, pybullet.connect(pybullet.DIRECT)


def _link_frame(p, body: int, client: int) -> tuple[np.ndarray, np.ndarray]:
    """World pose (pos, wxyz) of a body's base link frame (pybullet reports the inertial frame)."""
    pos, orn = p.getBasePositionAndOrientation(body, physicsClientId=client)
    local_pos, local_orn = p.getDynamicsInfo(body, -1, physicsClientId=client)[3:5]
    inv_pos, inv_orn = p.invertTransform(local_pos, local_orn)
    link_pos, link_orn = p.multiplyTransforms(pos, orn, inv_pos, inv_orn)
    x, y, z, w = link_orn
    return np.asarray(link_pos), np.asarray([w, x, y, z])


def urdf_bundle_load(folder: Path, visuals: bool = True, steps: int = 24) -> tuple[dict[str, tuple], dict[str, float]]:
    """Load a whole URDF bundle as its scene.json says, in pybullet DIRECT.

    Returns every object's root-link pose right after loading, and its vertical motion
    over `steps` steps under gravity with all contacts disabled (so a free object falls
    freely and a fixed one stays put). `visuals=False` skips visual meshes (speed).
    """
    p, client = _bullet()
    try:
        p.setGravity(0, 0, -9.81, physicsClientId=client)
        flags = 0 if visuals else p.URDF_IGNORE_VISUAL_SHAPES
        bundle = json.loads((folder / "scene.json").read_text())
        entries = list(bundle["objects"]) + ([dict(bundle["ground"], name=None)] if bundle["ground"] else [])
        bodies = {}
        for o in entries:
            body = p.loadURDF(str(folder / o["urdf"]), o["base_position"], o["base_orientation_xyzw"],
                              useFixedBase=o["use_fixed_base"], flags=flags, physicsClientId=client)
            for link in range(-1, p.getNumJoints(body, physicsClientId=client)):
                p.setCollisionFilterGroupMask(body, link, 0, 0, physicsClientId=client)
            if o["name"] is not None:
                bodies[o["name"]] = body
        poses = {n: _link_frame(p, b, client) for n, b in bodies.items()}
        for _ in range(steps):
            p.stepSimulation(physicsClientId=client)
        drops = {n: float(_link_frame(p, b, client)[0][2] - poses[n][0][2]) for n, b in bodies.items()}
        return poses, drops
    finally:
        p.disconnect(client)


def assert_free_fall(drops: dict[str, float], scene: dict, steps: int = 24, where: str = "") -> None:
    """Free objects fell g t^2 / 2 (within 15%), fixed ones did not move."""
    t = steps / 240
    for o in scene["objects"]:
        if o["static"] or o["camera"]:  # a camera is always fixed where it was sampled
            assert abs(drops[o["name"]]) < 1e-9, f"{where}{o['name']} (fixed) moved"
        else:
            assert abs(drops[o["name"]] + 0.5 * 9.81 * t * t) < 0.15 * 0.5 * 9.81 * t * t, f"{where}{o['name']} did not fall freely"


def urdf_validate(folder: Path) -> None:
    """yourdfpy validates every URDF of a bundle and every mesh it names exists."""
    import yourdfpy

    paths = sorted(folder.glob("*.urdf"))
    assert paths, f"no URDF in {folder}"
    for path in paths:
        robot = yourdfpy.URDF.load(str(path), load_meshes=False, build_scene_graph=True)
        assert robot.validate(), f"yourdfpy rejects {path.name}: {robot.errors}"
        for mesh in ET.parse(path).getroot().iter("mesh"):
            assert (folder / mesh.get("filename")).is_file(), f"{path.name}: missing mesh {mesh.get('filename')}"


def sdf_poses(path: Path) -> dict[str, tuple]:
    """pybullet.loadSDF the world; every model's base link pose by model name."""
    p, client = _bullet()
    try:
        bodies = p.loadSDF(str(path), physicsClientId=client)
        out = {}
        for body in bodies:
            name = p.getBodyInfo(body, physicsClientId=client)[1].decode()
            out[name] = _link_frame(p, body, client)
        return out
    finally:
        p.disconnect(client)


def sdf_joint_positions(path: Path) -> dict[tuple[str, str], float]:
    """The starting joint values an SDF world states (`<prsc:joint_positions>`): (model, joint) -> value."""
    from prsc.backends.sdf import JOINTS_NAMESPACE

    root = ET.parse(path).getroot()
    return {(e.get("model"), e.get("name")): float(e.text) for e in root.iter(f"{{{JOINTS_NAMESPACE}}}joint")}


def sdf_link_positions_at(path: Path, model: str, values: dict[str, float]) -> dict[str, np.ndarray]:
    """pybullet.loadSDF the world, set `model`'s joints to `values`, and return its links' world
    frame origins by link name (the bodies' frames, as MuJoCo's xpos gives them)."""
    p, client = _bullet()
    try:
        bodies = p.loadSDF(str(path), physicsClientId=client)
        body = next(b for b in bodies if p.getBodyInfo(b, physicsClientId=client)[1].decode() == model)
        joints = range(p.getNumJoints(body, physicsClientId=client))
        for j in joints:
            name = p.getJointInfo(body, j, physicsClientId=client)[1].decode()
            if name in values:
                p.resetJointState(body, j, values[name], physicsClientId=client)
        return {p.getJointInfo(body, j, physicsClientId=client)[12].decode():
                np.array(p.getLinkState(body, j, computeForwardKinematics=True, physicsClientId=client)[4])
                for j in joints}
    finally:
        p.disconnect(client)


def ign_check(path: Path) -> subprocess.CompletedProcess:
    """`ign sdf -k` on a file."""
    return subprocess.run(["ign", "sdf", "-k", str(path)], capture_output=True, text=True, timeout=120)


# ------------------------------------------------------------------ USD


def usd_errors(path: Path) -> list[str]:
    """Every error pxr.UsdValidation's validators report on the stage."""
    from pxr import Usd, UsdValidation

    stage = Usd.Stage.Open(str(path))
    validators = UsdValidation.ValidationRegistry().GetOrLoadAllValidators()
    errors = UsdValidation.ValidationContext(validators).Validate(stage)
    return [f"{e.GetName()}: {e.GetMessage()}" for e in errors if e.GetType() == UsdValidation.ValidationErrorType.Error]


def newton_load(path: Path) -> dict:
    """Load a USD stage in Newton (CPU) with its PhysX schema resolver, which reads the joints'
    starting values: {"joints": name -> value (rad or m), "kinematic": body names,
    "free": bodies on a free joint, "fk_gap": largest distance (m) between a body placed by
    Newton's forward kinematics from its joint values and the stage's own pose of it}."""
    import warp as wp

    wp.config.quiet = True
    import newton
    from newton.usd import SchemaResolverNewton, SchemaResolverPhysx
    from pxr import Usd, UsdGeom

    builder = newton.ModelBuilder()
    builder.add_usd(str(path), schema_resolvers=[SchemaResolverNewton(), SchemaResolverPhysx()])
    model = builder.finalize(device="cpu")
    q, starts, kinds = model.joint_q.numpy(), model.joint_q_start.numpy(), model.joint_type.numpy()
    moving = (int(newton.JointType.REVOLUTE), int(newton.JointType.PRISMATIC))
    joints = {label.rsplit("/", 1)[-1]: float(q[starts[j]]) for j, label in enumerate(model.joint_label) if kinds[j] in moving}
    state = model.state()
    newton.eval_fk(model, model.joint_q, model.joint_qd, state)
    placed = state.body_q.numpy()
    stage, cache = Usd.Stage.Open(str(path)), UsdGeom.XformCache()
    gap = max(float(np.linalg.norm(np.array(cache.GetLocalToWorldTransform(stage.GetPrimAtPath(label))).T[:3, 3] - placed[b, :3]))
              for b, label in enumerate(model.body_label))
    flags, child = model.body_flags.numpy(), model.joint_child.numpy()
    kinematic = {label.rsplit("/", 1)[-1] for b, label in enumerate(model.body_label) if flags[b] & int(newton.BodyFlags.KINEMATIC)}
    free = {model.body_label[child[j]].rsplit("/", 1)[-1] for j in range(model.joint_count) if kinds[j] == int(newton.JointType.FREE)}
    return {"joints": joints, "kinematic": kinematic, "free": free, "fk_gap": gap}


def usd_poses(path: Path, scene: dict) -> dict[str, tuple]:
    """World transform of /World/<object> for every object."""
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(str(path))
    cache = UsdGeom.XformCache()
    out = {}
    for o in scene["objects"]:
        prim = stage.GetPrimAtPath(f"/World/{o['name']}")
        assert prim.IsValid(), f"usd: no prim for {o['name']}"
        m = cache.GetLocalToWorldTransform(prim)
        # Gf matrices are row-vector: the rotation's rows are the local axes.
        rot = np.array([[m[i][j] for j in range(3)] for i in range(3)]).T
        from prsc.geometry.rotations import matrix_to_quat

        out[o["name"]] = (np.array([m[3][0], m[3][1], m[3][2]]), matrix_to_quat(rot))
    return out


# ------------------------------------------------------------------ Drake


def drake_load(path: Path):
    """pydrake's Parser loads a world (SDF or MJCF) into a finalised MultibodyPlant.

    Returns the plant, its default context, and the scene bodies by object name (for an SDF
    world the link named after the object in the model of that name; for MJCF the body).
    """
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant

    plant = MultibodyPlant(0.0)
    models = Parser(plant).AddModels(str(path))
    plant.Finalize()
    return plant, plant.CreateDefaultContext(), models


def drake_poses(plant, context, models, scene: dict) -> dict[str, tuple]:
    """World pose of every object's body in a loaded Drake plant, and whether it floats."""
    from prsc.geometry.rotations import matrix_to_quat

    names = {plant.GetModelInstanceName(m): m for m in models}
    out = {}
    for o in scene["objects"]:
        instance = names.get(o["name"], models[0])
        body = plant.GetBodyByName(o["name"], instance)
        pose = plant.EvalBodyPoseInWorld(context, body)
        out[o["name"]] = (pose.translation(), matrix_to_quat(pose.rotation().matrix()))
    return out


def drake_floating(plant, models, scene: dict) -> dict[str, bool]:
    """Whether each object's body is a free (floating-base) body in Drake."""
    names = {plant.GetModelInstanceName(m): m for m in models}
    out = {}
    for o in scene["objects"]:
        body = plant.GetBodyByName(o["name"], names.get(o["name"], models[0]))
        out[o["name"]] = body.is_floating_base_body()
    return out
