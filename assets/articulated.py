"""Articulated assets as the backends mount them: the user's own URDF or MJCF files and the
model library's arms (a file and what the library adds to it; docs/assets.md) behind one
frozen `RobotModel`.

Every format reads the same two sources: an MJCF tree to attach (`mjcf_spec`) and a URDF
with absolute mesh paths (`urdf`) that the URDF, SDF and USD writers convert. A user's
URDF is its own URDF with `package://` and relative paths resolved; a user's MJCF gets a
URDF written from its compiled model (prsc/assets/mjcf_urdf.py).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Sequence

from prsc.assets.urdf_tree import RobotTree, read_urdf
from prsc.user_assets.asset_files import (FORWARD_YAW, ArticulatedAsset, AssetJoint, asset_spec, build_root, describe_asset,
                                          file_spec, names_asset_file, resolve_asset_file)
from prsc.user_assets.asset_fitting import Fitting, library_arm
from prsc.errors import PrscError

GRAVITY_COMPENSATION_DAMPING = 2.0
"""Joint damping (N m s/rad or N s/m) given to an asset without actuators of its own."""

SERVO_FREQUENCY = 30.0
"""Natural frequency (rad/s) of the position servo prsc gives each joint of an asset without
actuators (a URDF has none): stiffness = inertia x frequency^2, critically damped, so a
heavy shoulder and a light wrist both settle (one gain for all makes the wrist unstable at
MuJoCo's 2 ms step). With gravity compensated, the servos only move the links."""

SERVO_ARMATURE = 0.01
"""Rotor inertia (kg m^2) added to each such joint: keeps a near-massless wrist stable."""


@dataclass(frozen=True)
class RobotModel:
    """One articulated asset as every backend and the runner mount it."""

    key: str  # names its folders in asset stores and its USD prim: "<stem>-<hash>"
    source: str  # the file it comes from
    folders: tuple[str, ...]  # where `package://` folders are looked up
    joints: tuple[AssetJoint, ...]  # in qpos order
    base_yaw: float  # yaw (rad, about +z) from the URDF's axes to the object's (the MJCF spec is turned already)
    root_offset: tuple[float, float, float]  # root frame from the box centre, at the file's home
    root: str  # the root link (body)
    tcp: str | None  # tool site or body
    servo_joints: tuple[str, ...]  # joints the file's own position servos hold; prsc gives the others servos
    passive: bool = False  # not a robot (no `tcp`: a cabinet): joints only damped, no servos, no gravity compensation
    fitting: Fitting | None = None  # what the model library adds to the file (a library arm)

    def mount_position(self, dimensions: tuple[float, float, float],
                       placed: Sequence[float] | None = None) -> tuple[float, float, float]:
        """The root frame in the object's (box centre) frame: `placed`, where the IR put it in the
        object's box (its `rootOffset`, at the object's joint values), else the file's at home."""
        if placed is not None:
            return tuple(float(v) for v in placed)  # type: ignore[return-value]
        return self.root_offset

    def home(self, joints: dict[str, float] | None = None) -> dict[str, float]:
        """Every joint's starting value: the asset's home, then the scene's `joints`."""
        values = {j.name: j.home for j in self.joints}
        values.update(joints or {})
        return values

    def mjcf_spec(self):
        """A fresh MjSpec of the asset (world body -> root), ready to attach."""
        spec = asset_spec(self.source, self.folders, self.fitting)
        for key in list(spec.keys):  # keyframes belong to the scene, which writes its own `home`
            spec.delete(key)
        # MuJoCo does not filter contacts between a child and a parent welded to the world
        # (a fixed base is): a link touching its base would jam its joint. Exclude them.
        for body in spec.bodies[1:]:
            parent = body.parent
            if parent is not None and parent.name and parent.name != "world":
                spec.add_exclude(bodyname1=parent.name, bodyname2=body.name)
        for first, second in self._touching_at_home(spec):
            spec.add_exclude(bodyname1=first, bodyname2=second)
        if self.passive:
            # Furniture: its joints move when something pushes or pulls them, damped.
            for joint in spec.joints:
                joint.damping = [GRAVITY_COMPENSATION_DAMPING, 0.0, 0.0]
                joint.armature = SERVO_ARMATURE
        elif any(joint.name not in self.servo_joints for joint in spec.joints):
            # Joints no servo of the file's holds (a URDF has no actuators; robosuite's arms have
            # torque motors, which stay, at 0): compensate gravity on every link, damp the joints,
            # and give each such joint a position servo named after it, force-limited to the
            # file's effort where it states one, so that it holds its pose and controllers can drive it.
            import mujoco

            for body in spec.bodies[1:]:
                body.gravcomp = 1.0
            for joint in spec.joints:  # at least prsc's damping and rotor inertia, or the file's own
                joint.damping = [max(float(joint.damping[0]), GRAVITY_COMPENSATION_DAMPING), 0.0, 0.0]
                joint.armature = max(float(joint.armature), SERVO_ARMATURE)
            inertia = spec.compile().dof_M0  # each joint's inertia at the reference pose
            names = {actuator.name for actuator in spec.actuators}
            for joint, moment in zip(spec.joints, inertia):
                if joint.name in self.servo_joints:
                    continue
                name = joint.name if joint.name not in names else f"{joint.name}_servo"
                servo = spec.add_actuator(name=name, target=joint.name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
                servo.set_to_position(kp=float(moment) * SERVO_FREQUENCY ** 2, kv=2 * float(moment) * SERVO_FREQUENCY)
                effort = joint.actfrcrange
                if effort[1] > effort[0]:
                    servo.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
                    servo.forcerange = list(effort)
        return spec

    def _touching_at_home(self, spec) -> list[tuple[str, str]]:
        """Pairs of the asset's bodies in contact at its home pose: a file whose home folds one
        link onto another (dm_control's Jaco; robosuite's Franka arm) would push them apart for ever,
        so such pairs do not collide, as its own simulator's self-collision filters have it."""
        import mujoco

        model = spec.compile()
        data = mujoco.MjData(model)
        for name, value in self.home().items():
            data.qpos[model.jnt_qposadr[model.joint(name).id]] = value
        mujoco.mj_forward(model, data)
        pairs = set()
        for contact in data.contact[:data.ncon]:
            bodies = sorted((model.body(model.geom_bodyid[contact.geom1]).name, model.body(model.geom_bodyid[contact.geom2]).name))
            if bodies[0] != bodies[1] and "world" not in bodies:
                pairs.add(tuple(bodies))
        return sorted(pairs)  # type: ignore[return-value]

    @property
    def prim_name(self) -> str:
        """The key as a USD prim name (letters, digits and `_`, not starting with a digit)."""
        name = re.sub(r"[^A-Za-z0-9_]", "_", self.key)
        return name if not name[0].isdigit() else "_" + name

    @property
    def urdf(self) -> Path:
        """A URDF of the asset, its mesh paths relative to its folder (built once, cached by
        the content of every file it reads: prsc/user_assets/asset_cache.py)."""
        return _urdf_path(self)


@lru_cache(maxsize=64)
def _file_model(path: str, folders: tuple[str, ...], passive: bool, fitting: Fitting | None = None) -> RobotModel:
    asset: ArticulatedAsset = describe_asset(path, folders, fitting)
    return RobotModel(asset.key, asset.source, folders, asset.joints, FORWARD_YAW, asset.root_offset, asset.root,
                      asset.tcp, asset.servo_joints, passive and not asset.actuators, fitting)


def robot_model(model: str | None, folders: Sequence[str] = (), passive: bool = False) -> RobotModel | None:
    """The articulated asset a scene object's `model` names, or None for any other model;
    `passive`: the object is no robot (it has no `tcp`), so a file without actuators gets none."""
    if model is None:
        return None
    if names_asset_file(model):
        return _file_model(str(resolve_asset_file(model, folders)), tuple(folders), passive)
    arm = library_arm(model)
    return None if arm is None else _file_model(str(arm.file), (), passive, arm.fitting)


CONVERSION_VERSION = "5"  # 5: keyed by every file the asset reads, its meshes copied into its folder
"""Bump when the URDF written for a file asset changes: its build folder's name carries it."""


def _build_folder(model: RobotModel) -> Path:
    return build_root() / "assets" / f"{model.key}-v{CONVERSION_VERSION}"


@lru_cache(maxsize=64)
def _urdf_path(model: RobotModel) -> Path:
    import xml.etree.ElementTree as ET

    from prsc.user_assets.asset_cache import bundle_urdf, entry_usable, write_entry

    target = _build_folder(model) / f"{Path(model.source).stem}.urdf"
    if not entry_usable(target):
        if Path(model.source).suffix.lower() == ".urdf":
            from prsc.user_assets.asset_files import urdf_with_absolute_paths

            root = bundle_urdf(ET.fromstring(urdf_with_absolute_paths(Path(model.source), model.folders)), target.parent)
        else:
            from prsc.assets.mjcf_urdf import mjcf_as_urdf

            target.parent.mkdir(parents=True, exist_ok=True)
            # In the file's own axes, as a URDF is read: the writers turn it by base_yaw.
            root = ET.fromstring(mjcf_as_urdf(file_spec(model.source, model.folders), target.parent))
        write_entry(target, root)
    return target


@lru_cache(maxsize=16)
def robot_tree(model: RobotModel) -> RobotTree:
    """The asset's URDF (a file's own, or the one written from its MJCF) parsed (cached)."""
    return read_urdf(model.urdf)


@lru_cache(maxsize=32)
def _link_names(model: RobotModel) -> frozenset[str]:
    return frozenset(link.name for link in robot_tree(model).links)


def check_robot_name(model: RobotModel, object_name: str) -> None:
    """An error when an object is named like one of its own links (the mount link would clash)."""
    if object_name in _link_names(model):
        raise PrscError(f"robot object {object_name!r} has the name of one of its {model.key} links; rename it")
