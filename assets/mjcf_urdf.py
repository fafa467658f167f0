"""A user's MJCF asset written as a URDF, so the URDF, SDF and USD writers (which read
URDF) carry it whole: every body a link, every hinge or slide a revolute, continuous or
prismatic joint with its axis and limits, every geom a visual and/or collision element.

Read from the compiled model at its reference configuration, so defaults, `euler`,
`fromto` and mesh recentring are already resolved: meshes are written as OBJ files of
the compiled vertices beside the URDF. URDF has no capsule or ellipsoid: a capsule is a
cylinder with a sphere at each end, an ellipsoid its enclosing sphere. A joint whose axis
does not pass through its body's origin moves the link frame onto the axis (URDF joints
turn about their child's origin). A body with more than one joint is an error.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from prsc.errors import PrscError
from prsc.files import atomic_write
from prsc.geometry.rotations import quat_to_matrix


def _num(value) -> str:
    """A number as URDF readers parse it: no exponent for round-off, no negative zero."""
    value = float(value)
    return format(0.0 if abs(value) < 1e-12 else value, ".12g")


def _nums(values) -> str:
    return " ".join(_num(v) for v in values)


def _rpy(matrix: np.ndarray) -> tuple[float, float, float]:
    """Fixed-axis roll, pitch, yaw (URDF) of a rotation matrix."""
    pitch = math.asin(max(-1.0, min(1.0, -matrix[2, 0])))
    if abs(math.cos(pitch)) > 1e-9:
        roll = math.atan2(matrix[2, 1], matrix[2, 2])
        yaw = math.atan2(matrix[1, 0], matrix[0, 0])
    else:
        roll, yaw = math.atan2(-matrix[1, 2], matrix[1, 1]), 0.0
    return roll, pitch, yaw


def _origin(parent: ET.Element, position, rotation: np.ndarray | None = None) -> None:
    rpy = _rpy(rotation) if rotation is not None else (0.0, 0.0, 0.0)
    ET.SubElement(parent, "origin", xyz=_nums(position), rpy=_nums(rpy))


def _mesh_file(model, mesh_id: int, folder: Path) -> Path:
    """The compiled mesh as an OBJ file in `folder` (written once per content)."""
    from prsc.user_assets.mesh_paths import obj_text

    start, count = model.mesh_vertadr[mesh_id], model.mesh_vertnum[mesh_id]
    face_start, face_count = model.mesh_faceadr[mesh_id], model.mesh_facenum[mesh_id]
    vertices = model.mesh_vert[start:start + count]
    faces = model.mesh_face[face_start:face_start + face_count]
    target = folder / "meshes" / f"mesh{mesh_id:03d}.obj"
    if not target.is_file():
        target.parent.mkdir(parents=True, exist_ok=True)
        atomic_write(target, obj_text(vertices, faces, ("prsc: a compiled MJCF mesh",)))
    return target


def _geometry_elements(model, g: int, folder: Path) -> list[tuple[ET.Element, np.ndarray, np.ndarray]]:
    """(geometry, position, rotation) of one geom in its body frame; a capsule gives three."""
    import mujoco

    kind = int(model.geom_type[g])
    size = model.geom_size[g]
    position, rotation = model.geom_pos[g].copy(), quat_to_matrix(model.geom_quat[g])
    if kind == int(mujoco.mjtGeom.mjGEOM_PLANE):
        return []
    geometry = ET.Element("geometry")
    if kind == int(mujoco.mjtGeom.mjGEOM_BOX):
        ET.SubElement(geometry, "box", size=_nums(2 * size))
    elif kind == int(mujoco.mjtGeom.mjGEOM_SPHERE):
        ET.SubElement(geometry, "sphere", radius=_num((size[0])))
    elif kind == int(mujoco.mjtGeom.mjGEOM_ELLIPSOID):
        ET.SubElement(geometry, "sphere", radius=_num((max(size))))
    elif kind in (int(mujoco.mjtGeom.mjGEOM_CYLINDER), int(mujoco.mjtGeom.mjGEOM_CAPSULE)):
        ET.SubElement(geometry, "cylinder", radius=_num((size[0])), length=_num((2 * size[1])))
        if kind == int(mujoco.mjtGeom.mjGEOM_CAPSULE):
            caps = []
            for sign in (-1.0, 1.0):
                cap = ET.Element("geometry")
                ET.SubElement(cap, "sphere", radius=_num((size[0])))
                caps.append((cap, position + rotation[:, 2] * sign * size[1], rotation))
            return [(geometry, position, rotation), *caps]
    elif kind == int(mujoco.mjtGeom.mjGEOM_MESH):
        path = _mesh_file(model, int(model.geom_dataid[g]), folder)
        ET.SubElement(geometry, "mesh", filename=path.relative_to(folder).as_posix())  # beside the URDF
    else:
        raise PrscError(f"geom {model.geom(g).name or g} has a type URDF cannot hold (height field or SDF)")
    return [(geometry, position, rotation)]


def mjcf_as_urdf(spec, folder: Path) -> str:
    """URDF text of an MJCF asset (its MjSpec), with meshes written into `folder`."""
    model = spec.compile()
    robot = ET.Element("robot", name=spec.modelname or "asset")
    names = [model.body(b).name or f"body{b}" for b in range(model.nbody)]
    shift = {0: np.zeros(3)}  # per body: where its link frame sits in the body frame
    for b in range(1, model.nbody):
        joints = [j for j in range(model.njnt) if model.jnt_bodyid[j] == b]
        if len(joints) > 1:
            raise PrscError(f"body {names[b]!r} has {len(joints)} joints; a URDF link moves by one")
        shift[b] = model.jnt_pos[joints[0]].copy() if joints else np.zeros(3)
        link = ET.SubElement(robot, "link", name=names[b])
        inertial = ET.SubElement(link, "inertial")
        _origin(inertial, model.body_ipos[b] - shift[b], quat_to_matrix(model.body_iquat[b]))
        ET.SubElement(inertial, "mass", value=_num((model.body_mass[b])))
        ixx, iyy, izz = (float(v) for v in model.body_inertia[b])
        ET.SubElement(inertial, "inertia", ixx=repr(ixx), ixy="0", ixz="0", iyy=repr(iyy), iyz="0", izz=repr(izz))
        for g in range(model.ngeom):
            if model.geom_bodyid[g] != b:
                continue
            collides = bool(model.geom_contype[g] or model.geom_conaffinity[g])
            rgba = model.mat_rgba[model.geom_matid[g]] if model.geom_matid[g] >= 0 else model.geom_rgba[g]
            visible = model.geom_group[g] <= 2 and rgba[3] > 0
            for geometry, position, rotation in _geometry_elements(model, g, folder):
                for tag, wanted in (("visual", visible), ("collision", collides)):
                    if not wanted:
                        continue
                    element = ET.SubElement(link, tag)
                    _origin(element, position - shift[b], rotation)
                    element.append(geometry)
                    if tag == "visual":
                        material = ET.SubElement(element, "material", name=f"{names[b]}_{g}")
                        ET.SubElement(material, "color", rgba=_nums(rgba))
        parent = int(model.body_parentid[b])
        parent_name = names[parent]
        if parent == 0:
            if not joints:
                continue  # the fixed root: prsc mounts it
            # A root that moves by a joint hangs from a massless base link where prsc mounts it.
            parent_name = f"{names[b]}_mount"
            ET.SubElement(robot, "link", name=parent_name)
        joint_name = model.joint(joints[0]).name if joints else f"{names[b]}_fixed"
        kind = "fixed"
        if joints:
            j = joints[0]
            hinge = int(model.jnt_type[j]) == 3
            kind = ("revolute" if model.jnt_limited[j] else "continuous") if hinge else "prismatic"
        element = ET.SubElement(robot, "joint", name=joint_name or f"joint{b}", type=kind)
        rotation = quat_to_matrix(model.body_quat[b])
        offset = model.body_pos[b] if parent else np.zeros(3)  # prsc places the root's origin
        _origin(element, offset + rotation @ shift[b] - shift[parent], rotation)
        ET.SubElement(element, "parent", link=parent_name)
        ET.SubElement(element, "child", link=names[b])
        if joints:
            j = joints[0]
            ET.SubElement(element, "axis", xyz=_nums(model.jnt_axis[j]))
            lower, upper = model.jnt_range[j] if model.jnt_limited[j] else (-1e9, 1e9)
            limit = ET.SubElement(element, "limit", effort="100", velocity="10")
            if kind != "continuous":
                limit.set("lower", _num((lower)))
                limit.set("upper", _num((upper)))
    ET.indent(robot, space="  ")
    return '<?xml version="1.0"?>\n' + ET.tostring(robot, encoding="unicode") + "\n"
