"""The user's own articulated assets (docs/assets.md): a URDF or MJCF file read into one
frozen description that the IR (sizes, joint checks), the constraint stage (`reachable by`),
the backends and the runner all read.

A file becomes a MuJoCo model in exactly one way, `asset_spec`: the file's own model
(`file_spec`) turned so that its +x, the ROS forward, is its object's ahead (+y;
docs/assets.md, "Forward"). In `file_spec` a URDF has its
`package://` and relative mesh paths resolved and MuJoCo's URDF import told to keep visual
geoms and static links (docs/assets.md); an MJCF has its asset paths made absolute, so
the model can be attached into any scene and saved anywhere. Inertias that break the
triangle inequality (the xArm's link2) are balanced by MuJoCo (`compiler.balanceinertia`),
in every file, as docs/assets.md says.

Foundation module: imported by every layer, it imports mujoco only inside functions.
"""

from __future__ import annotations

import hashlib
import math
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path
from typing import Sequence

from prsc.user_assets.asset_cache import input_stats, inputs_digest
from prsc.user_assets.asset_fitting import Fitting, library_arm
from prsc.user_assets.joint_servos import position_servo_joints
from prsc.user_assets.asset_inertia import unbalanced
from prsc.errors import PrscError
from prsc.user_assets.mesh_paths import mujoco_readable_meshes
from prsc.user_assets.urdf_source import parse_urdf, urdf_tree

ASSET_SUFFIXES = (".urdf", ".xml", ".mjcf")
"""File names that make `model "..."` a file of the user's own rather than a library name."""

ROOT_OFFSET = "rootOffset"
"""The property (and scene JSON `properties` key) holding where a file asset's root sits in its
object's box, from the box centre: the IR sets it from the box at the object's joint values."""
FORWARD_YAW = math.pi / 2
"""The turn (rad about +z) from a file's own axes to its object's: the file's +x, the ROS
forward, becomes the object's ahead (+y), where the built-in robot faces (docs/assets.md, "Forward")."""
JOINT_KINDS = {3: "revolute", 2: "prismatic"}
"""MuJoCo joint types (mjJNT_HINGE, mjJNT_SLIDE) the description keeps, by URDF name."""


def build_root() -> Path:
    """prsc's build folder for converted assets and caches: `$PRSC_BUILD_DIR`, default `<repo>/build`."""
    root = os.environ.get("PRSC_BUILD_DIR")
    return Path(root) if root else Path(__file__).resolve().parents[2] / "build"


def build_folder_error(error: OSError) -> PrscError | None:
    """`cannot write the build folder ROOT: ...` for an OSError met writing under it (a read-only
    or full build folder), else None: the build folder is prsc's cache, not the user's output."""
    root = build_root()
    if not error.filename or not os.path.abspath(os.fspath(error.filename)).startswith(str(root.absolute()) + os.sep):
        return None
    reason = os.strerror(error.errno) if error.errno else str(error)
    return PrscError(f"cannot write the build folder {root}: {error.filename}: {reason}; "
                     "point PRSC_BUILD_DIR at a writable folder")


def _converted_meshes() -> Path:
    """Where OBJ copies of the meshes MuJoCo cannot decode go (prsc.user_assets.urdf_source)."""
    return build_root() / "assets" / "converted"


def names_asset_file(model: object) -> bool:
    """Whether a `model` value names a URDF or MJCF file (else it is a library asset name)."""
    return isinstance(model, str) and model.strip().lower().endswith(ASSET_SUFFIXES)


def names_asset(model: object) -> bool:
    """Whether a `model` value names an asset read from a file: the user's URDF or MJCF, or a
    library arm (prsc/library/<model>.json: a file and what the library adds to it)."""
    return names_asset_file(model) or library_arm(model) is not None


@dataclass(frozen=True)
class AssetJoint:
    """One joint of an articulated asset: its kind, limits and starting value."""

    name: str
    kind: str  # "revolute" (rad) or "prismatic" (m)
    lower: float  # -inf/inf when the joint has no limits
    upper: float
    home: float  # the file's `home` keyframe value, else 0 clipped into the limits

    def admits(self, value: float) -> bool:
        """Whether `value` lies within the joint's limits (to 1e-9)."""
        return self.lower - 1e-9 <= value <= self.upper + 1e-9


@dataclass(frozen=True)
class ArticulatedAsset:
    """A URDF or MJCF asset as every stage sees it (lengths in m, angles in rad)."""

    source: str  # absolute path of the file
    digest: str  # sha256 of every file it reads (asset_cache.inputs_digest): the key of everything built from it
    format: str  # "urdf" or "mjcf"
    name: str  # the file's model name
    root: str  # the root body (link)
    links: tuple[str, ...]  # bodies (links), root first, in MuJoCo's order
    joints: tuple[AssetJoint, ...]  # hinge and slide joints in qpos order
    actuators: tuple[str, ...]
    sites: tuple[str, ...]
    tcp: str | None  # the tool frame: a site named `tcp`, else the last link of the longest chain
    box_low: tuple[float, float, float]  # the geometry's box (drawn and colliding) about the root's origin, at home
    box_high: tuple[float, float, float]
    fixed: bool = False  # a URDF whose root link has mass 0: fixed in the world, as pybullet loads it
    servo_joints: tuple[str, ...] = ()  # the joints a position servo of the file's own holds (not a torque motor)
    fitting: Fitting | None = None  # what the model library adds to the file (a library arm: asset_fitting.py)

    @property
    def key(self) -> str:
        """`<stem>-<digest>`: names its folders in build and asset stores."""
        return f"{Path(self.source).stem}-{self.digest[:10]}"

    @property
    def size(self) -> tuple[float, float, float]:
        """The box's extent (width x, length y, height z) at scale 1."""
        return tuple(h - l for l, h in zip(self.box_low, self.box_high))  # type: ignore[return-value]

    @property
    def root_offset(self) -> tuple[float, float, float]:
        """The root frame's origin relative to the box centre, at scale 1."""
        return tuple(-(l + h) / 2 for l, h in zip(self.box_low, self.box_high))  # type: ignore[return-value]

    @property
    def has_joints(self) -> bool:
        """Whether the asset is articulated (fixed-base unless `static False`)."""
        return bool(self.joints)

    def joint(self, name: str) -> AssetJoint | None:
        """The joint called `name`, or None."""
        return next((j for j in self.joints if j.name == name), None)

    def home(self, overrides: dict[str, float] | None = None) -> dict[str, float]:
        """Every joint's starting value, by name: the file's home, then `overrides`."""
        values = {j.name: j.home for j in self.joints}
        values.update(overrides or {})
        return values


def resolve_asset_file(raw: str, folders: Sequence[str]) -> Path:
    """The asset file `raw` names, looked up like meshes, or a PrscError saying where it looked."""
    from prsc.user_assets.mesh_paths import resolve_mesh

    return resolve_mesh(raw, folders, anywhere=True, what="asset")


def urdf_with_absolute_paths(path: Path, folders: Sequence[str] = ()) -> str:
    """The URDF's text with every mesh path absolute, for any URDF reader; a link whose
    inertial was dropped gets the one MuJoCo computes from its geometry, so every format
    carries the same masses."""
    root = urdf_tree(path, folders, _converted_meshes())
    for link in [link for link in root.findall("link") if unbalanced(link)]:
        link.remove(link.find("inertial"))
    missing = [link for link in root.findall("link") if link.find("inertial") is None]
    if missing:
        # MuJoCo's own values: computed from geometry, or balanced, exactly as the MJCF has them.
        model = asset_spec(path, folders).compile()
        for link in missing:
            body = model.body(link.get("name")).id
            inertial = ET.SubElement(link, "inertial")
            w, x, y, z = (float(v) for v in model.body_iquat[body])
            roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
            pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
            yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
            ET.SubElement(inertial, "origin", xyz=" ".join(repr(float(v)) for v in model.body_ipos[body]),
                          rpy=f"{roll!r} {pitch!r} {yaw!r}")
            ET.SubElement(inertial, "mass", value=repr(float(model.body_mass[body])))
            ixx, iyy, izz = (repr(float(v)) for v in model.body_inertia[body])
            ET.SubElement(inertial, "inertia", ixx=ixx, ixy="0", ixz="0", iyy=iyy, iyz="0", izz=izz)
    return '<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def _urdf_text(path: Path, folders: Sequence[str]) -> str:
    """The URDF with absolute mesh paths and MuJoCo's import told to keep visuals and links."""
    root = urdf_tree(path, folders, _converted_meshes())
    for extension in root.findall("mujoco"):
        root.remove(extension)
    extension = ET.SubElement(root, "mujoco")
    ET.SubElement(extension, "compiler", strippath="false", discardvisual="false", fusestatic="false",
                  balanceinertia="true", angle="radian")
    return ET.tostring(root, encoding="unicode")


def _absolute_asset_paths(spec, path: Path) -> None:
    """Make an MJCF's mesh, texture and height-field files absolute (attach drops meshdir)."""
    folder = path.parent
    for items, subfolder in ((spec.meshes, spec.meshdir), (spec.textures, spec.texturedir), (spec.hfields, "")):
        for item in items:
            if item.file and not os.path.isabs(item.file):
                item.file = str((folder / (subfolder or "") / item.file).resolve())
    spec.meshdir = ""
    spec.texturedir = ""


COLLISION_GROUP = 3
"""MuJoCo's renderer and viewer hide geom group 3 by default (the MJCF backend's own)."""


def _hide_collision_geoms(spec) -> None:
    """A URDF link's `<collision>` geoms in the hidden group where it has `<visual>` ones: drawn
    too, they would flicker through the visuals (a textured table top showing white triangles)."""
    drawn = {geom.parent.name for geom in spec.geoms if geom.contype == 0 and geom.conaffinity == 0}
    for geom in spec.geoms:
        if (geom.contype or geom.conaffinity) and geom.parent.name in drawn:
            geom.group = COLLISION_GROUP


def file_spec(path: Path | str, folders: Sequence[str] = ()):
    """A fresh `mujoco.MjSpec` of an asset file in the file's own axes (what writers of the
    file's own form read: its scaled copy, the URDF of an MJCF)."""
    import mujoco

    path = Path(path)
    try:
        if path.suffix.lower() == ".urdf":
            spec = mujoco.MjSpec.from_string(_urdf_text(path, folders))
            _hide_collision_geoms(spec)
        else:
            spec = mujoco.MjSpec.from_file(str(path))
            _absolute_asset_paths(spec, path)
            spec.compiler.balanceinertia = True
    except ValueError as error:  # MuJoCo's parse errors
        raise PrscError(f"cannot load {path.name} in MuJoCo: {str(error).strip().splitlines()[0]}") from None
    mujoco_readable_meshes(spec, build_root() / "assets")
    return spec


def asset_spec(path: Path | str, folders: Sequence[str] = (), fitting: Fitting | None = None):
    """A fresh `mujoco.MjSpec` of an asset file in its object's axes, ready to attach (the one
    file-to-model path): the file's model, what the library adds to it (`fitting`), turned by FORWARD_YAW."""
    spec = file_spec(path, folders)
    if fitting is not None:
        fitting.apply(spec)
    _turn_forward(spec)
    return spec


def model_asset(model: str, folders: Sequence[str] = ()) -> ArticulatedAsset:
    """The description of the asset a `model` names (`names_asset`): a library arm's fitted file,
    else the file looked up in `folders`."""
    arm = library_arm(model)
    if arm is not None:
        return describe_asset(arm.file, (), arm.fitting)
    return describe_asset(resolve_asset_file(model, folders), folders)


def _turn_forward(spec) -> None:
    """Turn everything the file places in its world by FORWARD_YAW about the world's origin."""
    import mujoco
    import numpy as np

    c, s = math.cos(FORWARD_YAW), math.sin(FORWARD_YAW)
    turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    yaw = np.array([math.cos(FORWARD_YAW / 2), 0.0, 0.0, math.sin(FORWARD_YAW / 2)])
    world = spec.worldbody
    for element in (*world.bodies, *world.frames, *world.geoms, *world.sites, *world.cameras):
        quat = np.array(element.quat, dtype=float)
        if element.alt.type != mujoco.mjtOrientation.mjORIENTATION_QUAT:
            quat = np.array(spec.resolve_orientation(spec.compiler.degree, spec.compiler.eulerseq, element.alt))
            element.alt.type = mujoco.mjtOrientation.mjORIENTATION_QUAT
        turned = np.zeros(4)
        mujoco.mju_mulQuat(turned, yaw, quat)
        element.quat = turned
        element.pos = turn @ np.asarray(element.pos, dtype=float)
        fromto = np.asarray(getattr(element, "fromto", [math.nan]), dtype=float)
        if not np.isnan(fromto).any():
            element.fromto = np.concatenate([turn @ fromto[:3], turn @ fromto[3:]])
    for light in world.lights:
        light.pos = turn @ np.asarray(light.pos, dtype=float)
        light.dir = turn @ np.asarray(light.dir, dtype=float)


def describe_asset(path: Path | str, folders: Sequence[str] = (), fitting: Fitting | None = None) -> ArticulatedAsset:
    """The description of an asset file, fitted (cached while it and every file it reads are unchanged)."""
    path = Path(path).resolve()
    return _describe(str(path), tuple(folders), input_stats(path, folders), fitting)


@lru_cache(maxsize=64)
def _describe(source: str, folders: tuple[str, ...], inputs: tuple[tuple[str, int, int], ...],
              fitting: Fitting | None) -> ArticulatedAsset:
    path = Path(source)
    spec = asset_spec(path, folders, fitting)
    try:
        model = spec.compile()
    except ValueError as error:
        raise PrscError(f"cannot load {path.name} in MuJoCo: {str(error).strip().splitlines()[0]}") from None
    roots = [b for b in range(1, model.nbody) if model.body_parentid[b] == 0]
    if len(roots) != 1:
        raise PrscError(f"{path.name} has {len(roots)} root bodies; an asset is one tree with one root")
    root = roots[0]
    if any(model.jnt_type[j] in (0, 1) for j in range(model.njnt)):  # free or ball joints
        raise PrscError(f"{path.name}: only revolute and prismatic joints are supported (it has a free or ball joint)")
    home_key = next((k for k in range(model.nkey) if model.key(k).name == "home"), None)
    qpos = model.key_qpos[home_key].copy() if home_key is not None else model.qpos0.copy()
    joints = []
    for j in range(model.njnt):
        lower, upper = (float(v) for v in model.jnt_range[j]) if model.jnt_limited[j] else (-math.inf, math.inf)
        value = float(qpos[model.jnt_qposadr[j]])
        if home_key is None:
            value = min(max(0.0, lower), upper)
            qpos[model.jnt_qposadr[j]] = value
        joints.append(AssetJoint(model.joint(j).name, JOINT_KINDS[int(model.jnt_type[j])], lower, upper, value))
    if model.ngeom == 0:
        raise PrscError(f"{path.name} has no geometry")
    low, high = _geometry_box(model, qpos, root)
    links = tuple(model.body(b).name for b in range(1, model.nbody))
    sites = tuple(model.site(s).name for s in range(model.nsite))
    digest = inputs_digest(path, folders)
    if fitting is not None:  # the fitted file is another asset: its reach and folders are its own
        digest = hashlib.sha256((digest + fitting.digest).encode()).hexdigest()
    return ArticulatedAsset(
        source=source, digest=digest, format="urdf" if path.suffix.lower() == ".urdf" else "mjcf",
        name=spec.modelname or path.stem, root=model.body(root).name, links=links, joints=tuple(joints),
        actuators=tuple(model.actuator(a).name for a in range(model.nu)), sites=sites,
        tcp=_tool_frame(model, sites), box_low=low, box_high=high,
        fixed=path.suffix.lower() == ".urdf" and _massless_root(path, model.body(root).name),
        servo_joints=position_servo_joints(model), fitting=fitting,
    )



def _geometry_box(model, qpos, root: int) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """The box (low and high corners) of every geom at joint positions `qpos`, about the root
    body's origin in the object's axes (asset_spec's; an MJCF root turned in its file stays turned)."""
    import mujoco
    import numpy as np

    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    # Every geom, drawn or colliding: pybullet's table.urdf collides with its top only, and its
    # legs, visual only, must stand on what the table is placed on.
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    points = []
    for g in range(model.ngeom):
        if model.geom_type[g] == int(mujoco.mjtGeom.mjGEOM_MESH):
            # The mesh's own vertices (in the geom frame): exact, where a box about them is not.
            mesh = model.geom_dataid[g]
            local = model.mesh_vert[model.mesh_vertadr[mesh]:model.mesh_vertadr[mesh] + model.mesh_vertnum[mesh]]
        else:
            centre, half = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
            local = centre + corners * half
        points.append(data.geom_xpos[g] + local @ data.geom_xmat[g].reshape(3, 3).T - data.xpos[root])
    stacked = np.concatenate(points)
    return tuple(float(v) for v in stacked.min(axis=0)), tuple(float(v) for v in stacked.max(axis=0))  # type: ignore[return-value]


def asset_at(asset: ArticulatedAsset, folders: Sequence[str], values: dict[str, float]) -> ArticulatedAsset:
    """The asset with its box at these joint values (the others at home): an object's box is
    the file's at the joint values its spec sets (docs/assets.md, "Size")."""
    homes = {joint.name: joint.home for joint in asset.joints}
    if all(values.get(name, home) == home for name, home in homes.items()):
        return asset
    low, high = _box_at(asset.source, tuple(folders), tuple(sorted({**homes, **values}.items())), asset.fitting)
    return replace(asset, box_low=low, box_high=high)


@lru_cache(maxsize=64)
def _box_at(source: str, folders: tuple[str, ...], values: tuple[tuple[str, float], ...], fitting: Fitting | None):
    model = asset_spec(Path(source), folders, fitting).compile()
    qpos = model.qpos0.copy()
    for name, value in values:
        qpos[model.jnt_qposadr[model.joint(name).id]] = value
    root = next(b for b in range(1, model.nbody) if model.body_parentid[b] == 0)
    return _geometry_box(model, qpos, root)


def _massless_root(path: Path, root: str) -> bool:
    """Whether a URDF's root link declares a mass of 0: pybullet's fixed base (its table.urdf and tray.urdf)."""
    link = next((e for e in parse_urdf(path).iter("link") if e.get("name") == root), None)
    mass = None if link is None else link.find("inertial/mass")
    try:
        return mass is not None and float(mass.get("value", "nan")) == 0.0
    except ValueError:
        return False


def _tool_frame(model, sites: tuple[str, ...]) -> str | None:
    """A site named `tcp`, else the last body of the longest chain (None without joints)."""
    if "tcp" in sites:
        return "tcp"
    if model.njnt == 0:
        return None
    depth = {0: 0}
    for b in range(1, model.nbody):
        depth[b] = depth[int(model.body_parentid[b])] + 1
    deepest = max(range(1, model.nbody), key=lambda b: (depth[b], -b))
    return model.body(deepest).name
