"""A URDF robot read into plain records (links, joints, geometry) with forward kinematics.

Used to convert a robot asset into formats that have no URDF import of their own (SDF
models, USD articulations). Only what a robot asset uses is read: inertials, mesh and
primitive geometry with origins and colours, revolute/continuous/prismatic/fixed joints
with axes, limits and mimics.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from prsc.geometry.kinematics import axis_angle
from prsc.geometry.rotations import rpy_to_matrix


@dataclass(frozen=True)
class Geometry:
    """A visual or collision element: a mesh file or a primitive, placed in its link."""

    kind: str  # mesh | box | cylinder | sphere
    origin: np.ndarray  # 4x4 in the link frame
    filename: str | None = None
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
    size: tuple[float, ...] = ()  # box: x y z; cylinder: radius, length; sphere: radius
    rgba: tuple[float, float, float, float] | None = None


@dataclass(frozen=True)
class Link:
    """A rigid link with its mass properties and geometry."""

    name: str
    mass: float
    inertial_origin: np.ndarray  # 4x4: centre of mass frame in the link frame
    inertia: np.ndarray  # 3x3 about the centre of mass, in the inertial frame
    visuals: tuple[Geometry, ...]
    collisions: tuple[Geometry, ...]


@dataclass(frozen=True)
class Joint:
    """A joint between two links; `origin` is the child frame in the parent at position 0."""

    name: str
    type: str  # revolute | continuous | prismatic | fixed
    parent: str
    child: str
    origin: np.ndarray
    axis: np.ndarray
    lower: float | None
    upper: float | None
    effort: float | None
    velocity: float | None
    mimic: tuple[str, float, float] | None  # (joint, multiplier, offset)


@dataclass(frozen=True)
class RobotTree:
    """A parsed URDF: links and joints in file order, and the root link."""

    name: str
    links: tuple[Link, ...]
    joints: tuple[Joint, ...]
    root: str

    def link(self, name: str) -> Link:
        """The link of that name."""
        return next(l for l in self.links if l.name == name)

    def link_poses(self, positions: dict[str, float] | None = None) -> dict[str, np.ndarray]:
        """4x4 pose of every link in the root link's frame at the given joint positions."""
        positions = positions or {}
        poses = {self.root: np.eye(4)}
        pending = list(self.joints)
        while pending:
            progressed = False
            for joint in list(pending):
                if joint.parent in poses:
                    poses[joint.child] = poses[joint.parent] @ joint.origin @ joint_motion(joint, positions.get(joint.name, 0.0))
                    pending.remove(joint)
                    progressed = True
            if not progressed:
                raise ValueError(f"URDF {self.name}: joints not connected to the root: {[j.name for j in pending]}")
        return poses


def joint_motion(joint: Joint, q: float) -> np.ndarray:
    """4x4 motion of a joint at position q, in its own frame."""
    out = np.eye(4)
    if joint.type in ("revolute", "continuous"):
        out[:3, :3] = axis_angle(joint.axis / np.linalg.norm(joint.axis), q)
    elif joint.type == "prismatic":
        out[:3, 3] = joint.axis / np.linalg.norm(joint.axis) * q
    return out


def _floats(text: str | None, default: tuple[float, ...]) -> tuple[float, ...]:
    return tuple(float(v) for v in text.split()) if text else default


def _origin(element: ET.Element | None) -> np.ndarray:
    out = np.eye(4)
    if element is not None:
        out[:3, :3] = rpy_to_matrix(_floats(element.get("rpy"), (0.0, 0.0, 0.0)))
        out[:3, 3] = _floats(element.get("xyz"), (0.0, 0.0, 0.0))
    return out


def _rgba(element: ET.Element, materials: dict[str, tuple[float, ...]]) -> tuple[float, float, float, float] | None:
    material = element.find("material")
    if material is None:
        return None
    color = material.find("color")
    if color is not None and color.get("rgba"):
        rgba = _floats(color.get("rgba"), (1.0, 1.0, 1.0, 1.0))
        if material.get("name"):
            materials[material.get("name")] = rgba
        return rgba  # type: ignore[return-value]
    return materials.get(material.get("name", ""))  # type: ignore[return-value]


def _geometry(element: ET.Element, materials: dict[str, tuple[float, ...]], base: Path) -> Geometry | None:
    geometry = element.find("geometry")
    if geometry is None or len(geometry) == 0:
        return None
    shape = geometry[0]
    origin = _origin(element.find("origin"))
    rgba = _rgba(element, materials)
    if shape.tag == "mesh":
        filename = shape.get("filename", "")
        path = Path(filename)
        if not path.is_absolute():
            path = base / path
        return Geometry("mesh", origin, str(path), _floats(shape.get("scale"), (1.0, 1.0, 1.0)), rgba=rgba)  # type: ignore[arg-type]
    if shape.tag == "box":
        return Geometry("box", origin, size=_floats(shape.get("size"), (1.0, 1.0, 1.0)), rgba=rgba)
    if shape.tag == "cylinder":
        return Geometry("cylinder", origin, size=(float(shape.get("radius", 0)), float(shape.get("length", 0))), rgba=rgba)
    if shape.tag == "sphere":
        return Geometry("sphere", origin, size=(float(shape.get("radius", 0)),), rgba=rgba)
    return None


def _inertia(element: ET.Element | None) -> tuple[float, np.ndarray, np.ndarray]:
    if element is None:
        return 0.0, np.eye(4), np.zeros((3, 3))
    mass_el = element.find("mass")
    mass = float(mass_el.get("value", 0.0)) if mass_el is not None else 0.0
    i = element.find("inertia")
    get = (lambda k: float(i.get(k, 0.0))) if i is not None else (lambda k: 0.0)
    tensor = np.array(
        [
            [get("ixx"), get("ixy"), get("ixz")],
            [get("ixy"), get("iyy"), get("iyz")],
            [get("ixz"), get("iyz"), get("izz")],
        ]
    )
    return mass, _origin(element.find("origin")), tensor


def _limit(element: ET.Element | None, key: str) -> float | None:
    if element is None or element.get(key) is None:
        return None
    return float(element.get(key))


def read_urdf(path: Path | str) -> RobotTree:
    """Parse a URDF file into a RobotTree (relative mesh paths resolved against its folder)."""
    path = Path(path)
    root = ET.parse(path).getroot()
    materials: dict[str, tuple[float, ...]] = {}
    for material in root.findall("material"):
        color = material.find("color")
        if color is not None and material.get("name"):
            materials[material.get("name")] = _floats(color.get("rgba"), (1.0, 1.0, 1.0, 1.0))
    links = []
    for link in root.findall("link"):
        mass, inertial_origin, tensor = _inertia(link.find("inertial"))
        visuals = tuple(g for g in (_geometry(v, materials, path.parent) for v in link.findall("visual")) if g)
        collisions = tuple(g for g in (_geometry(c, materials, path.parent) for c in link.findall("collision")) if g)
        links.append(Link(link.get("name"), mass, inertial_origin, tensor, visuals, collisions))
    joints = []
    for joint in root.findall("joint"):
        limit = joint.find("limit")
        mimic = joint.find("mimic")
        joints.append(
            Joint(
                name=joint.get("name"),
                type=joint.get("type"),
                parent=joint.find("parent").get("link"),
                child=joint.find("child").get("link"),
                origin=_origin(joint.find("origin")),
                axis=np.asarray(_floats(joint.find("axis").get("xyz") if joint.find("axis") is not None else None, (1.0, 0.0, 0.0))),
                lower=_limit(limit, "lower"),
                upper=_limit(limit, "upper"),
                effort=_limit(limit, "effort"),
                velocity=_limit(limit, "velocity"),
                mimic=(mimic.get("joint"), float(mimic.get("multiplier", 1.0)), float(mimic.get("offset", 0.0)))
                if mimic is not None
                else None,
            )
        )
    children = {j.child for j in joints}
    roots = [l.name for l in links if l.name not in children]
    if len(roots) != 1:
        raise ValueError(f"URDF {path} has {len(roots)} root links, expected 1")
    return RobotTree(root.get("name", path.stem), tuple(links), tuple(joints), roots[0])
