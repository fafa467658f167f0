"""Franka Emika Panda, converted at build time from the URDF and meshes pybullet ships.

The recipe reads `pybullet_data/franka_panda/panda.urdf` (Apache-2.0, see the LICENSE.txt
beside it), and writes two files into a cached build folder, nothing downloaded:

- `panda.urdf`: mesh paths made absolute, the `panda_` name prefix dropped (joints are
  `joint1..joint7`, `finger_joint1/2`; links `link0..link8`, `hand`, `leftfinger`,
  `rightfinger`, `tcp`), and the placeholder inertias (`0.1 0.1 0.1` everywhere) replaced
  by mass properties computed from the collision meshes: a total of `TOTAL_MASS` kg shared
  by convex-hull volume, each link a uniform solid.
- `panda.xml`: the same robot as MJCF with visual meshes (group 2) and collision meshes
  (group 3), joint damping and armature, gravity compensation, position actuators on the
  seven arm joints and one `gripper` actuator driving both fingers (the URDF `<mimic>`
  becomes a joint equality), a `tcp` site between the fingertips, and the base yawed by
  +90 degrees so the arm reaches along +y of its base frame.

The build folder is `$PRSC_BUILD_DIR/assets/` (default `<repo>/build/assets/`); each build
lives in a subfolder keyed by a hash of the source URDF, its location and this recipe's
version, so a second call reuses it without rewriting anything. Files are written to a
temporary name and renamed into place, so concurrent workers never see a partial file.
"""

from __future__ import annotations

import hashlib
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from prsc.assets.simulation import set_simulation_options
from prsc.files import atomic_write

# Bump when the conversion changes: the cache key includes it.
RECIPE_VERSION = "3"

PANDA_BASE_YAW = math.pi / 2
"""Yaw (rad, about +z) from the URDF base frame (arm along +x) to the prsc base frame (+y)."""

ARM_JOINTS: tuple[str, ...] = tuple(f"joint{i}" for i in range(1, 8))
"""The seven arm joints, base to wrist (same names in the URDF and the MJCF)."""

FINGER_JOINTS: tuple[str, str] = ("finger_joint1", "finger_joint2")
"""The two prismatic finger joints; the second mirrors the first (URDF mimic / MJCF equality)."""

ARM_ACTUATORS: tuple[str, ...] = ARM_JOINTS
"""MJCF position actuators, one per arm joint and named after it."""

GRIPPER_ACTUATOR = "gripper"
"""MJCF position actuator on `finger_joint1`; ctrl is one finger's opening in metres."""

TCP_SITE = "tcp"
"""MJCF site (and URDF link) at the tool centre between the fingertips."""

BASE_BODY = "base"
"""Root body of the MJCF: origin at the bottom centre of the base, arm along its +y."""

HOME_QPOS: tuple[float, ...] = (0.0, -math.pi / 4, 0.0, -3 * math.pi / 4, 0.0, math.pi / 2, math.pi / 4)
"""Home configuration of the seven arm joints (rad): gripper pointing down in front of the base."""

GRIPPER_OPEN = 0.04
"""Gripper actuator target for fully open fingers (each finger 4 cm from the centre)."""

GRIPPER_CLOSED = 0.0
"""Gripper actuator target for fully closed fingers."""

TOTAL_MASS = 18.0
"""Total mass (kg) of the arm and hand, shared between links by collision-mesh volume."""

TCP_OFFSET = 0.1034
"""Distance (m) of the tool centre from the hand frame along its +z (Franka's default TCP)."""

# Position-servo gains (N m/rad, N m s/rad) and torque limits (N m) per arm joint; the
# limits are the URDF efforts, the gains those of MuJoCo Menagerie's Panda.
_ARM_KP = (4500.0, 4500.0, 3500.0, 3500.0, 2000.0, 2000.0, 2000.0)
_ARM_KV = (450.0, 450.0, 350.0, 350.0, 200.0, 200.0, 200.0)
_ARM_FORCE = (87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0)
_JOINT_DAMPING = 1.0
_JOINT_ARMATURE = 0.1
# Gripper: a stiff position servo saturating at the URDF finger effort (20 N).
_GRIPPER_KP = 2000.0
_GRIPPER_KV = 20.0
_GRIPPER_FORCE = 20.0
# Links without a collision mesh (the flange and the tcp frame) get a negligible solid.
_DUMMY_MASS = 1e-3
_DUMMY_INERTIA = 4e-8


def _source_dir() -> Path:
    """The franka_panda folder inside the installed pybullet_data package."""
    import pybullet_data

    return Path(pybullet_data.getDataPath()) / "franka_panda"


def _repo_root() -> Path:
    """The repository root (this file is <repo>/assets/panda.py)."""
    return Path(__file__).resolve().parents[1]


def build_dir() -> Path:
    """The asset build folder: `$PRSC_BUILD_DIR/assets`, default `<repo>/build/assets`."""
    from prsc.user_assets.asset_files import build_root

    return build_root() / "assets"


def _cache_dir() -> Path:
    """The folder of this build, keyed by the source URDF, its location and the recipe."""
    source = _source_dir() / "panda.urdf"
    digest = hashlib.sha256()
    digest.update(RECIPE_VERSION.encode())
    digest.update(str(source.resolve()).encode())
    digest.update(source.read_bytes())
    return build_dir() / f"panda-{digest.hexdigest()[:12]}"


def _rpy_matrix(rpy: tuple[float, float, float]) -> np.ndarray:
    """Rotation matrix of URDF fixed-axis roll, pitch, yaw (X then Y then Z)."""
    r, p, y = rpy
    cx, sx, cy, sy, cz, sz = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def _floats(text: str | None, default: tuple[float, ...]) -> tuple[float, ...]:
    """Parse a whitespace-separated float list, or return a default."""
    return tuple(float(v) for v in text.split()) if text else default


def _collision_hull(link: ET.Element):
    """The convex hull (trimesh) of a link's collision meshes in the link frame, or None."""
    import trimesh

    from prsc.user_assets.mesh_paths import read_trimesh

    parts = []
    for collision in link.findall("collision"):
        mesh = collision.find("geometry/mesh")
        if mesh is None:
            continue
        loaded = read_trimesh(mesh.get("filename"), force="mesh")
        origin = collision.find("origin")
        transform = np.eye(4)
        if origin is not None:
            transform[:3, :3] = _rpy_matrix(_floats(origin.get("rpy"), (0.0, 0.0, 0.0)))
            transform[:3, 3] = _floats(origin.get("xyz"), (0.0, 0.0, 0.0))
        loaded.apply_transform(transform)
        parts.append(loaded)
    if not parts:
        return None
    # The shipped collision meshes are convex but not watertight: their hull is the solid.
    return trimesh.util.concatenate(parts).convex_hull


def _set_inertial(link: ET.Element, mass: float, com: np.ndarray, inertia: np.ndarray) -> None:
    """Replace a link's <inertial> with the given mass, centre of mass and inertia tensor."""
    for old in link.findall("inertial"):
        link.remove(old)
    inertial = ET.Element("inertial")
    ET.SubElement(inertial, "origin", xyz=" ".join(f"{v:.9g}" for v in com), rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=f"{mass:.9g}")
    names = {"ixx": (0, 0), "ixy": (0, 1), "ixz": (0, 2), "iyy": (1, 1), "iyz": (1, 2), "izz": (2, 2)}
    ET.SubElement(inertial, "inertia", {k: f"{inertia[i, j]:.9g}" for k, (i, j) in names.items()})
    link.insert(0, inertial)


def _converted_urdf() -> ET.ElementTree:
    """The shipped URDF with absolute mesh paths, short names, a tcp link and real inertias."""
    source = _source_dir()
    tree = ET.parse(source / "panda.urdf")
    robot = tree.getroot()
    mesh_root = source.resolve()

    def short(name: str) -> str:
        return name[len("panda_"):] if name.startswith("panda_") else name

    for element in robot.iter():
        if element.tag in ("link", "joint") and element.get("name"):
            element.set("name", short(element.get("name")))
        if element.tag in ("parent", "child", "mimic") and element.get("link"):
            element.set("link", short(element.get("link")))
        if element.tag == "mimic" and element.get("joint"):
            element.set("joint", short(element.get("joint")))
    # The grasp-target frame becomes the tcp, at the same offset as the MJCF site.
    for link in robot.findall("link"):
        if link.get("name") == "grasptarget":
            link.set("name", TCP_SITE)
    for joint in robot.findall("joint"):
        if joint.get("name") == "grasptarget_hand":
            joint.set("name", "tcp_joint")
            joint.find("child").set("link", TCP_SITE)
            joint.find("origin").set("xyz", f"0 0 {TCP_OFFSET}")
    # pybullet-only contact tags mean nothing elsewhere; friction is set in the MJCF.
    for link in robot.findall("link"):
        for contact in link.findall("contact"):
            link.remove(contact)

    for mesh in robot.iter("mesh"):
        filename = mesh.get("filename")
        if filename.startswith("package://"):
            filename = filename[len("package://"):]
        mesh.set("filename", str(mesh_root / filename))

    hulls = {link.get("name"): _collision_hull(link) for link in robot.findall("link")}
    total_volume = sum(h.volume for h in hulls.values() if h is not None)
    for link in robot.findall("link"):
        hull = hulls[link.get("name")]
        if hull is None:
            _set_inertial(link, _DUMMY_MASS, np.zeros(3), np.eye(3) * _DUMMY_INERTIA)
            continue
        mass = TOTAL_MASS * hull.volume / total_volume
        hull.density = mass / hull.volume
        _set_inertial(link, mass, np.asarray(hull.center_mass), np.asarray(hull.moment_inertia))

    return tree


def _urdf_text(tree: ET.ElementTree) -> str:
    """Serialise a URDF tree with an XML declaration."""
    ET.indent(tree, space="  ")
    return '<?xml version="1.0"?>\n' + ET.tostring(tree.getroot(), encoding="unicode") + "\n"


def _clean_visual_meshes(tree: ET.ElementTree, folder: Path) -> dict[str, str]:
    """Re-export each visual OBJ as a plain OBJ in `folder`; map old path to new path.

    The shipped visual OBJs carry malformed texture coordinates that MuJoCo warns about on
    every compile (and MuJoCo ignores their .mtl colours anyway), so the copies keep only
    vertices and faces. They stay OBJ because Drake's MuJoCo parser reads no other mesh
    format (docs/backends.md).
    """
    import trimesh

    from prsc.user_assets.mesh_paths import read_trimesh

    mapping = {}
    for visual in tree.getroot().iter("visual"):
        mesh = visual.find("geometry/mesh")
        if mesh is None or mesh.get("filename") in mapping:
            continue
        source = Path(mesh.get("filename"))
        if "visual" not in source.parts:
            continue  # visuals that reuse a collision mesh are clean already
        target = folder / "meshes" / f"{source.stem}.obj"
        target.parent.mkdir(parents=True, exist_ok=True)
        loaded = read_trimesh(str(source), force="mesh", process=False)
        text = trimesh.exchange.obj.export_obj(
            loaded, include_normals=False, include_color=False, include_texture=False, write_texture=False
        )
        atomic_write(target, text.encode("utf-8"))
        mapping[str(source)] = str(target)
    return mapping


def _mujoco_urdf_text(tree: ET.ElementTree, visual_meshes: dict[str, str]) -> str:
    """The URDF for MuJoCo's importer: compiler hints, a yawed `base` root, no tcp link.

    The hints keep visual geoms and static links; the extra root link makes the arm reach
    along +y of `base`; the tcp frame becomes an MJCF site instead of a dummy body; visual
    meshes point to their cleaned copies.
    """
    robot = ET.fromstring(_urdf_text(tree).split("\n", 1)[1])
    for visual in robot.iter("visual"):
        mesh = visual.find("geometry/mesh")
        if mesh is not None and mesh.get("filename") in visual_meshes:
            mesh.set("filename", visual_meshes[mesh.get("filename")])
    hints = ET.Element("mujoco")
    ET.SubElement(
        hints,
        "compiler",
        strippath="false",
        discardvisual="false",
        fusestatic="false",
        balanceinertia="false",
        angle="radian",
    )
    robot.insert(0, hints)
    for link in robot.findall("link"):
        if link.get("name") == TCP_SITE:
            robot.remove(link)
    for joint in robot.findall("joint"):
        if joint.find("child").get("link") == TCP_SITE:
            robot.remove(joint)
    robot.insert(1, ET.Element("link", name=BASE_BODY))
    base_joint = ET.Element("joint", name="base_joint", type="fixed")
    ET.SubElement(base_joint, "parent", link=BASE_BODY)
    ET.SubElement(base_joint, "child", link="link0")
    ET.SubElement(base_joint, "origin", xyz="0 0 0", rpy=f"0 0 {PANDA_BASE_YAW!r}")
    robot.insert(2, base_joint)
    return ET.tostring(robot, encoding="unicode")


def _mjcf_from_urdf(urdf_tree: ET.ElementTree, visual_meshes: dict[str, str]):
    """Build the MjSpec of one actuated Panda from the converted URDF."""
    import mujoco

    spec = mujoco.MjSpec.from_string(_mujoco_urdf_text(urdf_tree, visual_meshes))
    spec.compile()  # resolves the URDF into bodies, geoms and the mimic equality

    # Visual and collision geoms come in URDF order: tell them apart by contact flags.
    for geom in spec.geoms:
        if geom.contype == 0 and geom.conaffinity == 0:
            geom.group = 2
        else:
            geom.group = 3
            geom.rgba = [0.5, 0.5, 0.5, 1.0]
    for body in spec.bodies:
        if body.name in ("world", BASE_BODY, "link0"):
            continue
        body.gravcomp = 1.0
    for name in ARM_JOINTS:
        joint = spec.joint(name)
        joint.damping = [_JOINT_DAMPING, 0.0, 0.0]
        joint.armature = _JOINT_ARMATURE
    for name in FINGER_JOINTS:
        joint = spec.joint(name)
        joint.damping = [_JOINT_DAMPING, 0.0, 0.0]
    # Grippy fingertips: torsional friction stops a held cube from spinning about the grip axis.
    for finger in ("leftfinger", "rightfinger"):
        for geom in spec.body(finger).geoms:
            if geom.group == 3:
                geom.friction = [1.5, 0.02, 0.001]
                geom.condim = 4
                geom.priority = 1
    spec.body("hand").add_site(name=TCP_SITE, pos=[0.0, 0.0, TCP_OFFSET], size=[0.005, 0, 0], group=4)
    # A colour scheme close to the real arm: white links, dark hand and fingers.
    for body in ("hand", "leftfinger", "rightfinger"):
        for geom in spec.body(body).geoms:
            if geom.group == 2:
                geom.rgba = [0.25, 0.25, 0.25, 1.0]
    for geom in spec.geoms:
        if geom.group == 2 and geom.parent.name not in ("hand", "leftfinger", "rightfinger"):
            geom.rgba = [0.95, 0.95, 0.95, 1.0]

    spec.modelname = "panda"
    set_simulation_options(spec.option)
    for equality in spec.equalities:
        equality.name = "finger_mimic"
        equality.solref = [0.005, 1.0]
    for name, kp, kv, force in zip(ARM_ACTUATORS, _ARM_KP, _ARM_KV, _ARM_FORCE):
        actuator = spec.add_actuator(name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        actuator.set_to_position(kp=kp, kv=kv)
        actuator.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        actuator.forcerange = [-force, force]
        actuator.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
        actuator.ctrlrange = list(spec.joint(name).range)
    gripper = spec.add_actuator(name=GRIPPER_ACTUATOR, target=FINGER_JOINTS[0], trntype=mujoco.mjtTrn.mjTRN_JOINT)
    gripper.set_to_position(kp=_GRIPPER_KP, kv=_GRIPPER_KV)
    gripper.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
    gripper.forcerange = [-_GRIPPER_FORCE, _GRIPPER_FORCE]
    gripper.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
    gripper.ctrlrange = [GRIPPER_CLOSED, GRIPPER_OPEN]
    spec.add_key(
        name="home",
        qpos=list(HOME_QPOS) + [GRIPPER_OPEN, GRIPPER_OPEN],
        ctrl=list(HOME_QPOS) + [GRIPPER_OPEN],
    )
    return spec


def _ensure_built() -> Path:
    """Convert the Panda once into the cache folder and return that folder."""
    folder = _cache_dir()
    urdf_path, mjcf_path = folder / "panda.urdf", folder / "panda.xml"
    if urdf_path.is_file() and mjcf_path.is_file():
        return folder
    tree = _converted_urdf()
    folder.mkdir(parents=True, exist_ok=True)
    atomic_write(urdf_path, _urdf_text(tree))
    spec = _mjcf_from_urdf(tree, _clean_visual_meshes(tree, folder))
    xml = spec.to_xml()
    atomic_write(mjcf_path, xml)
    return folder


def panda_urdf_path() -> Path:
    """Path of the converted Panda URDF (absolute mesh paths, real inertias), built on first use.

    Its root link `link0` is the base with the arm reaching along +x, as in the original:
    the +90 degree yaw that makes the arm reach along the prsc base frame's +y is NOT
    applied here; URDF consumers (pybullet, yourdfpy, USD, SDF) compose `PANDA_BASE_YAW`
    about +z into the base placement themselves.
    """
    return _ensure_built() / "panda.urdf"


def panda_mjcf_path() -> Path:
    """Path of a standalone MJCF of one actuated Panda (arm along +y, absolute mesh paths).

    It loads with `mujoco.MjModel.from_xml_path` from any working directory and holds a
    keyframe `home` (arm at `HOME_QPOS`, gripper open).
    """
    return _ensure_built() / "panda.xml"


def panda_mjcf_spec():
    """A fresh `mujoco.MjSpec` of one Panda, ready to attach under a scene body.

    World body -> `base` (origin at the bottom centre of the base, arm reaching along +y)
    -> `link0` ... `hand` -> `leftfinger`/`rightfinger`. Actuators `joint1..joint7`
    (position servos) and `gripper` (ctrl = one finger's opening, 0 closed .. 0.04 open);
    site `tcp` between the fingertips. The scene should set the options this spec carries
    (`integrator="implicitfast"`: the servo damping is stiff for explicit Euler; and for
    grasping `cone="elliptic"`, `impratio="10"`); MuJoCo keeps the parent's options and
    warns on attach when they differ. Attach with
    `frame.attach_body(spec.body("base"), "r1/", "")` or `parent.attach(spec, prefix=...)`.
    """
    import mujoco

    spec = mujoco.MjSpec.from_file(str(panda_mjcf_path()))
    # Keyframes belong to the scene (their qpos would not match it): drop them. The options
    # stay: a scene that sets the same ones attaches without conflict warnings.
    for key in list(spec.keys):
        spec.delete(key)
    spec.nkey = 0
    return spec
