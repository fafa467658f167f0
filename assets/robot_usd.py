"""A robot URDF converted to a USD articulation asset (UsdPhysics), built once and cached.

The asset's default prim `/<robot>` carries ArticulationRootAPI; every link is a flat child
Xform (no nested rigid bodies) with RigidBodyAPI and MassAPI, placed at the robot's home
posture, with its visual meshes converted by trimesh to UsdGeom.Mesh (boxes, cylinders and
spheres as UsdGeom Cube, Cylinder and Sphere) and its collision geometry as colliders
(meshes as convex hulls; purpose "guide", not rendered). Joints live under
`/<robot>/joints`: revolute joints with limits in degrees and prismatic joints in metres,
each with a drive holding the home posture (furniture: none); `root_joint` is a fixed joint from the world
to the root link, whose world-side frame (`physics:localPos0/localRot0`) a scene sets to
where it mounts the robot. Mimic joints (a gripper's second finger) have no UsdPhysics
schema and are left as independent joints.
"""

from __future__ import annotations

import hashlib
import math
from pathlib import Path

import numpy as np

from prsc.assets.urdf_tree import Joint, RobotTree, read_urdf
from prsc.files import atomic_path
from prsc.geometry.rotations import matrix_to_quat

RECIPE_VERSION = "4"  # 2: URDF boxes, cylinders and spheres converted too; 3: joint states; 4: a massless link authors no inertia

# Drive gains per unit of joint motion: angular drives in USD are per degree.
_ANGULAR_STIFFNESS = 1000.0 * math.pi / 180  # N m / deg
_ANGULAR_DAMPING = 100.0 * math.pi / 180  # N m s / deg
_LINEAR_STIFFNESS = 2000.0  # N / m
_LINEAR_DAMPING = 20.0  # N s / m


def _build_dir() -> Path:
    from prsc.user_assets.asset_files import build_root

    return build_root() / "assets"


def robot_usd_cached(robot: str, urdf_path: Path, home: dict[str, float], drives: bool = True) -> Path:
    """Path of the robot's USD asset (default prim `/<robot>`, a valid prim name), posed at
    `home` (joint name -> value), converting it on first use (keyed by URDF, home, drives and
    recipe). Without `drives` (furniture) its joints are free to move."""
    digest = hashlib.sha256()
    digest.update(RECIPE_VERSION.encode())
    digest.update(Path(urdf_path).read_bytes())
    digest.update(repr(sorted(home.items())).encode())
    digest.update(b"drives" if drives else b"free")
    target = _build_dir() / f"{robot}-usd-{digest.hexdigest()[:12]}" / f"{robot}.usdc"
    if not target.is_file():
        target.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(target) as tmp:
            _write_robot_usd(robot, read_urdf(urdf_path), home, tmp, drives)
    return target


def _valid_names(names: list[str], reserved: set[str]) -> dict[str, str]:
    """Each name as a USD prim name: itself where USD allows it, else made valid
    (Tf.MakeValidIdentifier: `base_link-inertia` -> `base_link_inertia`), and unique."""
    from pxr import Tf

    taken = set(reserved)
    out: dict[str, str] = {}
    for name in names:
        valid = candidate = Tf.MakeValidIdentifier(name)
        k = 1
        while candidate in taken:
            candidate = f"{valid}_{k}"
            k += 1
        taken.add(candidate)
        out[name] = candidate
    return out


def prim_names(tree: RobotTree) -> tuple[dict[str, str], dict[str, str]]:
    """The prim names of a tree's links (under the root, beside `joints`) and joints (under
    `joints`, beside `root_joint`): URDF and MJCF names may hold `-`, `.` or `/`, USD's may not."""
    return (_valid_names([link.name for link in tree.links], {"joints"}),
            _valid_names([joint.name for joint in tree.joints], {"root_joint"}))


def drive_attribute(joint: Joint) -> str:
    """The attribute of a joint's drive target (`drive:angular:...` in degrees, `linear` in m)."""
    return f"drive:{'linear' if joint.type == 'prismatic' else 'angular'}:physics:targetPosition"


def state_attribute(joint: Joint) -> str:
    """The attribute of a joint's starting value (`state:angular:...` in degrees, `linear` in m).

    UsdPhysics has no joint state; this is PhysX's JointStateAPI, which Isaac Sim reads and
    Newton reads with its PhysX schema resolver. A reduced-coordinate simulator starts each
    joint there; the links' poses say the same for one that reads maximal coordinates."""
    return f"state:{'linear' if joint.type == 'prismatic' else 'angular'}:physics:position"


def joint_state_schema(joint: Joint) -> str:
    """The applied schema that carries `state_attribute` (multiple-apply, one per axis kind)."""
    return f"PhysxJointStateAPI:{'linear' if joint.type == 'prismatic' else 'angular'}"


def usd_joint_value(joint: Joint, value: float) -> float:
    """A joint value in USD's units: degrees for a revolute joint, metres for a prismatic one."""
    return float(value) if joint.type == "prismatic" else math.degrees(value)


def _quatd(matrix: np.ndarray):
    from pxr import Gf

    w, x, y, z = matrix_to_quat(matrix)
    return Gf.Quatd(float(w), Gf.Vec3d(float(x), float(y), float(z)))


def _quatf(matrix: np.ndarray):
    from pxr import Gf

    w, x, y, z = matrix_to_quat(matrix)
    return Gf.Quatf(float(w), Gf.Vec3f(float(x), float(y), float(z)))


def set_pose(xformable, matrix: np.ndarray) -> None:
    """Author translate + orient (double precision) ops from a 4x4 pose."""
    from pxr import Gf, UsdGeom

    xformable.AddTranslateOp(UsdGeom.XformOp.PrecisionDouble).Set(Gf.Vec3d(*(float(v) for v in matrix[:3, 3])))
    xformable.AddOrientOp(UsdGeom.XformOp.PrecisionDouble).Set(_quatd(matrix[:3, :3]))


def _mesh_prim(stage, path: str, filename: str, origin: np.ndarray, scale, rgba=None):
    """A UsdGeom.Mesh converted from a mesh file with trimesh."""
    from prsc.user_assets.mesh_paths import read_trimesh
    from pxr import Gf, UsdGeom, Vt

    mesh = read_trimesh(filename, force="mesh")
    prim = UsdGeom.Mesh.Define(stage, path)
    vertices = np.asarray(mesh.vertices, dtype=np.float32)
    prim.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(vertices))
    prim.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(mesh.faces), 3, dtype=np.int32)))
    prim.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(np.asarray(mesh.faces, dtype=np.int32).reshape(-1)))
    prim.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    prim.CreateExtentAttr(Vt.Vec3fArray([Gf.Vec3f(*low.tolist()), Gf.Vec3f(*high.tolist())]))
    return _placed(prim, origin, scale, rgba)


def _placed(prim, origin: np.ndarray, scale, rgba):
    """`prim` at `origin` in its link, scaled (when not 1) and coloured (when given)."""
    from pxr import Gf

    set_pose(prim, origin)
    if tuple(scale) != (1.0, 1.0, 1.0):
        prim.AddScaleOp().Set(Gf.Vec3f(*(float(s) for s in scale)))
    if rgba is not None:
        prim.CreateDisplayColorAttr([Gf.Vec3f(*(float(c) for c in rgba[:3]))])
        prim.CreateDisplayOpacityAttr([float(rgba[3])])
    return prim


def _primitive_prim(stage, path: str, geometry, rgba=None):
    """A UsdGeom Cube (scaled), Cylinder (about z, as URDF's) or Sphere for a URDF primitive."""
    from pxr import Gf, UsdGeom

    if geometry.kind == "box":
        prim = UsdGeom.Cube.Define(stage, path)
        prim.CreateSizeAttr(1.0)
        prim.CreateExtentAttr([Gf.Vec3f(-0.5, -0.5, -0.5), Gf.Vec3f(0.5, 0.5, 0.5)])
    elif geometry.kind == "cylinder":
        prim = UsdGeom.Cylinder.Define(stage, path)
        radius, length = (float(v) for v in geometry.size)
        prim.CreateRadiusAttr(radius)
        prim.CreateHeightAttr(length)
        prim.CreateAxisAttr(UsdGeom.Tokens.z)
        prim.CreateExtentAttr([Gf.Vec3f(-radius, -radius, -length / 2), Gf.Vec3f(radius, radius, length / 2)])
    else:
        prim = UsdGeom.Sphere.Define(stage, path)
        radius = float(geometry.size[0])
        prim.CreateRadiusAttr(radius)
        prim.CreateExtentAttr([Gf.Vec3f(-radius, -radius, -radius), Gf.Vec3f(radius, radius, radius)])
    return _placed(prim, geometry.origin, geometry.size if geometry.kind == "box" else (1.0, 1.0, 1.0), rgba)


def _geometry_prim(stage, path: str, geometry, rgba=None):
    """The prim of a URDF visual or collision element: a converted mesh or a primitive."""
    if geometry.kind == "mesh":
        return _mesh_prim(stage, path, geometry.filename, geometry.origin, geometry.scale, rgba)
    return _primitive_prim(stage, path, geometry, rgba)


def apply_mass(prim, mass: float, com, tensor: np.ndarray) -> None:
    """MassAPI with mass, centre of mass, principal moments and principal axes."""
    from pxr import Gf, UsdPhysics

    api = UsdPhysics.MassAPI.Apply(prim)
    api.CreateMassAttr(float(mass))
    api.CreateCenterOfMassAttr(Gf.Vec3f(*(float(v) for v in com)))
    tensor = (np.asarray(tensor, dtype=float) + np.asarray(tensor, dtype=float).T) / 2
    off = abs(tensor[0, 1]) + abs(tensor[0, 2]) + abs(tensor[1, 2])
    if off <= 1e-12 * max(np.trace(tensor), 1e-300):
        diagonal, axes = np.diag(tensor), np.eye(3)
    else:
        diagonal, axes = np.linalg.eigh(tensor)
        if np.linalg.det(axes) < 0:
            axes[:, 2] *= -1.0
    if not (diagonal > 0).all():  # a massless frame (a URDF's tool link): UsdPhysics wants both or neither
        return
    api.CreateDiagonalInertiaAttr(Gf.Vec3f(*(float(v) for v in diagonal)))
    api.CreatePrincipalAxesAttr(_quatf(axes))


def _axis_frame(axis: np.ndarray) -> np.ndarray:
    """A rotation taking +X to the unit joint axis (UsdPhysics joints move about X, Y or Z)."""
    a = axis / np.linalg.norm(axis)
    x = np.array([1.0, 0.0, 0.0])
    c = float(a @ x)
    v = np.cross(x, a)
    s = float(np.linalg.norm(v))
    if s < 1e-12:
        return np.eye(3) if c > 0 else np.diag([-1.0, -1.0, 1.0])
    k = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]]) / s
    return np.eye(3) + s * k + (1 - c) * (k @ k)


def _joint(stage, root: str, joint: Joint, home: dict[str, float], drives: bool,
           names: tuple[dict[str, str], dict[str, str]]) -> None:
    from pxr import Gf, Sdf, UsdPhysics

    links, joints = names
    path = f"{root}/joints/{joints[joint.name]}"
    frame = _axis_frame(joint.axis) if joint.type != "fixed" else np.eye(3)
    if joint.type == "fixed":
        usd = UsdPhysics.FixedJoint.Define(stage, path)
    elif joint.type in ("revolute", "continuous"):
        usd = UsdPhysics.RevoluteJoint.Define(stage, path)
        usd.CreateAxisAttr("X")
        if joint.type == "revolute" and joint.lower is not None and joint.upper is not None:
            usd.CreateLowerLimitAttr(math.degrees(joint.lower))
            usd.CreateUpperLimitAttr(math.degrees(joint.upper))
    elif joint.type == "prismatic":
        usd = UsdPhysics.PrismaticJoint.Define(stage, path)
        usd.CreateAxisAttr("X")
        if joint.lower is not None and joint.upper is not None:
            usd.CreateLowerLimitAttr(joint.lower)
            usd.CreateUpperLimitAttr(joint.upper)
    else:
        raise ValueError(f"joint {joint.name}: type {joint.type!r} has no USD equivalent")
    usd.CreateBody0Rel().SetTargets([Sdf.Path(f"{root}/{links[joint.parent]}")])
    usd.CreateBody1Rel().SetTargets([Sdf.Path(f"{root}/{links[joint.child]}")])
    usd.CreateLocalPos0Attr(Gf.Vec3f(*(float(v) for v in joint.origin[:3, 3])))
    usd.CreateLocalRot0Attr(_quatf(joint.origin[:3, :3] @ frame))
    usd.CreateLocalPos1Attr(Gf.Vec3f(0.0, 0.0, 0.0))
    usd.CreateLocalRot1Attr(_quatf(frame))
    if joint.type != "fixed":
        usd.GetPrim().AddAppliedSchema(joint_state_schema(joint))
        usd.GetPrim().CreateAttribute(state_attribute(joint), Sdf.ValueTypeNames.Float).Set(
            usd_joint_value(joint, home.get(joint.name, 0.0)))
    if drives and joint.type in ("revolute", "continuous", "prismatic"):
        angular = joint.type != "prismatic"
        drive = UsdPhysics.DriveAPI.Apply(usd.GetPrim(), "angular" if angular else "linear")
        drive.CreateTypeAttr("force")
        drive.CreateStiffnessAttr(_ANGULAR_STIFFNESS if angular else _LINEAR_STIFFNESS)
        drive.CreateDampingAttr(_ANGULAR_DAMPING if angular else _LINEAR_DAMPING)
        drive.CreateTargetPositionAttr(usd_joint_value(joint, home.get(joint.name, 0.0)))
        if joint.effort:
            drive.CreateMaxForceAttr(joint.effort)


def _write_robot_usd(robot: str, tree: RobotTree, home: dict[str, float], path: Path, drives: bool = True) -> None:
    """Convert a parsed URDF into a USD articulation file at `path`."""
    from pxr import Sdf, Usd, UsdGeom, UsdPhysics

    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    UsdPhysics.SetStageKilogramsPerUnit(stage, 1.0)
    root = f"/{robot}"
    top = UsdGeom.Xform.Define(stage, root)
    stage.SetDefaultPrim(top.GetPrim())
    UsdPhysics.ArticulationRootAPI.Apply(top.GetPrim())
    poses = tree.link_poses(home)
    names = prim_names(tree)
    for link in tree.links:
        prim = f"{root}/{names[0][link.name]}"
        xform = UsdGeom.Xform.Define(stage, prim)
        set_pose(xform, poses[link.name])
        UsdPhysics.RigidBodyAPI.Apply(xform.GetPrim())
        rot = link.inertial_origin[:3, :3]
        apply_mass(xform.GetPrim(), link.mass, link.inertial_origin[:3, 3], rot @ link.inertia @ rot.T)
        for k, geometry in enumerate(link.visuals):
            _geometry_prim(stage, f"{prim}/visual_{k}", geometry, geometry.rgba)
        for k, geometry in enumerate(link.collisions):
            collider = _geometry_prim(stage, f"{prim}/collision_{k}", geometry)
            collider.CreatePurposeAttr(UsdGeom.Tokens.guide)
            UsdPhysics.CollisionAPI.Apply(collider.GetPrim())
            if geometry.kind == "mesh":
                UsdPhysics.MeshCollisionAPI.Apply(collider.GetPrim()).CreateApproximationAttr(UsdPhysics.Tokens.convexHull)
    UsdGeom.Scope.Define(stage, f"{root}/joints")
    for joint in tree.joints:
        _joint(stage, root, joint, home, drives, names)
    fixed = UsdPhysics.FixedJoint.Define(stage, f"{root}/joints/root_joint")
    fixed.CreateBody1Rel().SetTargets([Sdf.Path(f"{root}/{names[0][tree.root]}")])
    stage.GetRootLayer().Save()
