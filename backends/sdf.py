"""SDF backend: one world per scene with a model per object (SDFormat 1.9).

Poses are written as `x y z roll pitch yaw` (pybullet's loadSDF ignores quaternion
formats). Each model is named after its object and its first link (the one pybullet
takes as the base) carries the object's name too and sits at the object's pose. Static
objects are `<static>1</static>` models (pybullet reads the flag with atoi, so not
"true"). A robot is a model whose first link, named after the object, is a massless mount
at the box centre, welded by a fixed joint to the robot's base at the bottom centre; its
links sit at the zero configuration and each joint axis is written in the joint (child
link) frame, as in URDF. A fixed-base robot is a non-static model welded to the world by a
fixed joint written at world level (`//world/joint`, parent `world`, child `<robot>::<mount>`),
and its mount link is massless. Each simulator reads that form: Drake and Gazebo weld the
mount (a static model with moving joints is refused by Drake, and its joints do not move in
Gazebo); pybullet skips world-level joints, and a base link of mass 0 is fixed in pybullet
(it cannot parse a joint whose parent is "world" inside a model). A camera object carries a
camera `<sensor>` looking along the object's +y.

Where each robot's joints start (the scene's `joints`, the asset's home for the rest) is
stated in the world as a custom element, `<prsc:joint_positions>` holding one
`<prsc:joint model="M" name="J">value</prsc:joint>` per moving joint (SDFormat's custom
elements: a prefix declared with `xmlns:prsc` on `<sdf>`, JOINTS_NAMESPACE). Link poses stay at
the zero configuration, because SDF measures joint values from the poses written. SDFormat
has no element that every reader takes: `<axis><initial_position>` is gone from 1.9's schema
and Drake's parser refuses it, and the world `<state>` (Gazebo's saved worlds) is refused by
Drake too. Readers that do not know the prefix skip the element (Drake with one warning);
pybullet loads at zero, and docs/backends.md shows the three lines that set the joints.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from functools import lru_cache
from pathlib import Path

import numpy as np

from prsc.assets.urdf_tree import Geometry
from prsc.backends.bodies import Body, light_directions, resolve_bodies
from prsc.backends.gazebo_camera import camera_sensor_body
from prsc.backends.inertia import Inertial
from prsc.backends.mjcf import FRICTION
from prsc.backends.numbers import num, nums
from prsc.backends.scene import GROUND_HALF_SIZE, Scene
from prsc.assets.articulated import RobotModel, check_robot_name, robot_tree
from prsc.backends.store import AssetStore, relative_path
from prsc.backends.xmltext import element_text, placeholder, serialise
from prsc.geometry.rotations import matrix_to_rpy, quat_to_rpy, rot_z

SDF_VERSION = "1.9"
JOINTS_NAMESPACE = "urn:prsc:sdf:joint-positions"  # the `prsc:` prefix of the joints' starting values


def _pose(parent: ET.Element, xyz, quat=None, rpy=None, relative_to: str | None = None) -> None:
    if rpy is None:
        rpy = quat_to_rpy(quat) if quat is not None else (0.0, 0.0, 0.0)
    pose = ET.SubElement(parent, "pose")
    if relative_to:
        pose.set("relative_to", relative_to)
    pose.text = nums(list(xyz) + list(rpy))


def _matrix_pose(parent: ET.Element, matrix: np.ndarray, relative_to: str | None = None) -> None:
    _pose(parent, matrix[:3, 3], rpy=matrix_to_rpy(matrix[:3, :3]), relative_to=relative_to)


def _inertial(link: ET.Element, mass: float, com, tensor) -> None:
    inertial = ET.SubElement(link, "inertial")
    _pose(inertial, com)
    ET.SubElement(inertial, "mass").text = num(mass)
    inertia = ET.SubElement(inertial, "inertia")
    for key, (i, j) in (("ixx", (0, 0)), ("ixy", (0, 1)), ("ixz", (0, 2)), ("iyy", (1, 1)), ("iyz", (1, 2)), ("izz", (2, 2))):
        ET.SubElement(inertia, key).text = num(tensor[i][j])


def _material(parent: ET.Element, rgba) -> None:
    material = ET.SubElement(parent, "material")
    ET.SubElement(material, "ambient").text = nums(rgba)
    ET.SubElement(material, "diffuse").text = nums(rgba)


def _surface(collision: ET.Element) -> None:
    ode = ET.SubElement(ET.SubElement(ET.SubElement(collision, "surface"), "friction"), "ode")
    ET.SubElement(ode, "mu").text = num(FRICTION[0])
    ET.SubElement(ode, "mu2").text = num(FRICTION[0])


def _part_geometry(parent: ET.Element, part, folder: Path) -> None:
    geometry = ET.SubElement(parent, "geometry")
    if part.shape == "box":
        ET.SubElement(ET.SubElement(geometry, "box"), "size").text = nums(part.size)
    elif part.shape == "cylinder":
        cylinder = ET.SubElement(geometry, "cylinder")
        ET.SubElement(cylinder, "radius").text = num(part.radius)
        ET.SubElement(cylinder, "length").text = num(part.size[2])
    elif part.shape == "sphere":
        ET.SubElement(ET.SubElement(geometry, "sphere"), "radius").text = num(part.radius)
    else:
        mesh = ET.SubElement(geometry, "mesh")
        ET.SubElement(mesh, "uri").text = relative_path(part.mesh, folder)
        ET.SubElement(mesh, "scale").text = nums(part.size)


def _parts_model(world: ET.Element, body: Body, folder: Path) -> None:
    obj = body.obj
    model = ET.SubElement(world, "model", name=obj.name)
    # pybullet reads <static> with atoi(): only "1" makes a model fixed ("true" reads as 0).
    ET.SubElement(model, "static").text = "1" if body.fixed else "0"
    _pose(model, obj.position, obj.quaternion)
    link = ET.SubElement(model, "link", name=obj.name)
    inertial: Inertial = body.inertial
    _inertial(link, inertial.mass, inertial.com, inertial.tensor)
    for part in body.parts:
        if part.collides:
            collision = ET.SubElement(link, "collision", name=f"{part.name}_collision")
            _pose(collision, part.position, part.quaternion)
            _part_geometry(collision, part, folder)
            _surface(collision)
        if not part.visible:
            continue
        visual = ET.SubElement(link, "visual", name=f"{part.name}_visual")
        _pose(visual, part.position, part.quaternion)
        _part_geometry(visual, part, folder)
        if part.texture is None:
            _material(visual, obj.color)
        elif part.shape != "mesh":  # a textured mesh's OBJ names its material and image (a <material> would override them)
            _material(visual, (1.0, 1.0, 1.0, 1.0))
            metal = ET.SubElement(ET.SubElement(visual.find("material"), "pbr"), "metal")
            ET.SubElement(metal, "albedo_map").text = relative_path(part.texture, folder)
    if body.camera is not None:
        sensor = ET.SubElement(link, "sensor", name=obj.name, type="camera")
        camera_sensor_body(sensor, body.camera)
        ET.SubElement(sensor, "always_on").text = "true"
        ET.SubElement(sensor, "update_rate").text = "30"


def _robot_geometry(parent: ET.Element, geometry: Geometry, robot: RobotModel, store: AssetStore, folder: Path) -> None:
    element = ET.SubElement(parent, "geometry")
    if geometry.kind == "mesh":
        mesh = ET.SubElement(element, "mesh")
        ET.SubElement(mesh, "uri").text = relative_path(store.robot_file(robot.key, geometry.filename), folder)
        if geometry.scale != (1.0, 1.0, 1.0):
            ET.SubElement(mesh, "scale").text = nums(geometry.scale)
    elif geometry.kind == "box":
        ET.SubElement(ET.SubElement(element, "box"), "size").text = nums(geometry.size)
    elif geometry.kind == "cylinder":
        cylinder = ET.SubElement(element, "cylinder")
        ET.SubElement(cylinder, "radius").text = num(geometry.size[0])
        ET.SubElement(cylinder, "length").text = num(geometry.size[1])
    else:
        ET.SubElement(ET.SubElement(element, "sphere"), "radius").text = num(geometry.size[0])


@lru_cache(maxsize=64)
def _robot_links_text(robot: RobotModel, store_root: str, folder: str, mount: tuple[float, float, float]) -> tuple[str, ...]:
    """The robot's links and joints as SDF text in the model (object) frame (cached).

    Links sit at the zero configuration, the base at `mount` and yawed so the arm reaches
    along the model's +y. (pybullet ignores a base link's own pose, so the model frame
    is the object's and the mount offset goes into every link pose.)
    """
    store = AssetStore(store_root)
    tree = robot_tree(robot)
    holder = ET.Element("model")
    base = np.eye(4)
    base[:3, :3] = rot_z(robot.base_yaw)
    base[:3, 3] = mount
    poses = tree.link_poses()
    for link in tree.links:
        element = ET.SubElement(holder, "link", name=link.name)
        _matrix_pose(element, base @ poses[link.name])
        com = link.inertial_origin
        _inertial(element, link.mass, com[:3, 3], com[:3, :3] @ link.inertia @ com[:3, :3].T)
        for k, geometry in enumerate(link.collisions):
            collision = ET.SubElement(element, "collision", name=f"collision_{k}")
            _matrix_pose(collision, geometry.origin)
            _robot_geometry(collision, geometry, robot, store, Path(folder))
        for k, geometry in enumerate(link.visuals):
            visual = ET.SubElement(element, "visual", name=f"visual_{k}")
            _matrix_pose(visual, geometry.origin)
            _robot_geometry(visual, geometry, robot, store, Path(folder))
            if geometry.rgba is not None:
                _material(visual, geometry.rgba)
    for joint in tree.joints:
        kind = {"continuous": "revolute"}.get(joint.type, joint.type)
        element = ET.SubElement(holder, "joint", name=joint.name, type=kind)
        ET.SubElement(element, "parent").text = joint.parent
        ET.SubElement(element, "child").text = joint.child
        if kind == "fixed":
            continue
        # The joint frame is the child link frame, as in URDF: the axis carries over as is
        # (SDF 1.9's default frame for it, and the one pybullet reads).
        axis = ET.SubElement(element, "axis")
        ET.SubElement(axis, "xyz").text = nums(joint.axis / np.linalg.norm(joint.axis))
        limit = ET.SubElement(axis, "limit")
        if joint.type != "continuous" and joint.lower is not None and joint.upper is not None:
            ET.SubElement(limit, "lower").text = num(joint.lower)
            ET.SubElement(limit, "upper").text = num(joint.upper)
        if joint.effort is not None:
            ET.SubElement(limit, "effort").text = num(joint.effort)
        if joint.velocity is not None:
            ET.SubElement(limit, "velocity").text = num(joint.velocity)
    return ("\n".join(element_text(child) for child in holder),)


def _robot_model(world: ET.Element, body: Body, store: AssetStore, folder: Path, pieces: list[str]) -> None:
    """The robot as an SDF model at the object's pose; its first link, named after the
    object, is the mount (welded to the robot's base, and to the world when fixed)."""
    obj = body.obj
    assert body.robot is not None
    tree = robot_tree(body.robot)
    check_robot_name(body.robot, obj.name)
    model = ET.SubElement(world, "model", name=obj.name)
    _pose(model, obj.position, obj.quaternion)
    # Never static: Drake refuses a static model with moving joints (module docstring).
    ET.SubElement(model, "static").text = "0"
    link = ET.SubElement(model, "link", name=obj.name)
    if body.fixed:
        # Mass 0 is what fixes a base link in pybullet, which skips the world weld below.
        _inertial(link, 0.0, (0.0, 0.0, 0.0), np.zeros((3, 3)))
    else:
        _inertial(link, body.inertial.mass, body.inertial.com, body.inertial.tensor)
    joint = ET.SubElement(model, "joint", name=f"{obj.name}_mount", type="fixed")
    ET.SubElement(joint, "parent").text = obj.name
    ET.SubElement(joint, "child").text = tree.root
    for text in _robot_links_text(body.robot, str(store.root), str(folder), body.mount_position):
        placeholder(model, pieces, text)


def _world_weld(world: ET.Element, name: str) -> None:
    """A world-level fixed joint from `world` to the mount link of robot model `name`."""
    joint = ET.SubElement(world, "joint", name=f"{name}_world_weld", type="fixed")
    ET.SubElement(joint, "parent").text = "world"
    ET.SubElement(joint, "child").text = f"{name}::{name}"


def _joint_positions(world: ET.Element, bodies: tuple[Body, ...]) -> None:
    """`<prsc:joint_positions>`: every moving joint of every robot at its starting value (module docstring)."""
    robots = [body for body in bodies if body.robot is not None]
    if not robots:
        return
    holder = ET.SubElement(world, "prsc:joint_positions")
    for body in robots:
        assert body.robot is not None
        values = body.robot.home(dict(body.obj.joints))
        for joint in robot_tree(body.robot).joints:
            if joint.type != "fixed" and joint.name in values:
                ET.SubElement(holder, "prsc:joint", model=body.obj.name, name=joint.name).text = num(values[joint.name])


def _ground_model(world: ET.Element, name: str) -> None:
    model = ET.SubElement(world, "model", name=name)
    ET.SubElement(model, "static").text = "1"
    link = ET.SubElement(model, "link", name="link")
    _inertial(link, 0.0, (0.0, 0.0, 0.0), np.zeros((3, 3)))
    for tag in ("collision", "visual"):
        element = ET.SubElement(link, tag, name=tag)
        plane = ET.SubElement(ET.SubElement(element, "geometry"), "plane")
        ET.SubElement(plane, "normal").text = "0 0 1"
        ET.SubElement(plane, "size").text = nums((2 * GROUND_HALF_SIZE, 2 * GROUND_HALF_SIZE))
        if tag == "collision":
            _surface(element)
        else:
            _material(element, (0.8, 0.8, 0.78, 1.0))


def _light(world: ET.Element, body: Body) -> None:
    """A light object: an SDF `<light>` of the world where the object is, its direction the object's +y."""
    light = body.light
    assert light is not None
    element = ET.SubElement(world, "light", name=body.obj.name, type=light.kind)
    ET.SubElement(element, "cast_shadows").text = "true" if light.cast_shadow else "false"
    _pose(element, body.obj.position, (1.0, 0.0, 0.0, 0.0))
    ET.SubElement(element, "diffuse").text = nums((*light.color, 1.0))  # a colour: each component in [0, 1]
    ET.SubElement(element, "intensity").text = num(light.intensity)  # SDF 1.9
    ET.SubElement(element, "specular").text = "0.1 0.1 0.1 1"
    ET.SubElement(element, "direction").text = nums(light_directions(body.obj.quaternion)[0])
    if light.kind == "spot":
        spot = ET.SubElement(element, "spot")
        ET.SubElement(spot, "inner_angle").text = "0"
        ET.SubElement(spot, "outer_angle").text = num(math.radians(light.cutoff))
        ET.SubElement(spot, "falloff").text = "1"


def sdf_text(scene: Scene, path: Path, store: AssetStore) -> str:
    """The SDF world of a scene to be written at `path` (mesh URIs relative to it)."""
    folder = Path(path).parent
    bodies = resolve_bodies(scene, store)
    root = ET.Element("sdf", {"version": SDF_VERSION, "xmlns:prsc": JOINTS_NAMESPACE})
    world = ET.SubElement(root, "world", name=f"scene_{scene.index}")
    ET.SubElement(world, "gravity").text = "0 0 -9.81"
    if scene.ground:
        names = {b.name for b in bodies}
        ground = "ground_plane"
        while ground in names:
            ground = "_" + ground
        _ground_model(world, ground)
    pieces: list[str] = []
    for body in bodies:
        if body.light is not None:
            _light(world, body)
        elif body.robot is not None:
            _robot_model(world, body, store, folder, pieces)
        else:
            _parts_model(world, body, folder)
    for body in bodies:
        if body.robot is not None and body.fixed:
            _world_weld(world, body.obj.name)
    _joint_positions(world, bodies)
    return '<?xml version="1.0"?>\n' + serialise(root, pieces) + "\n"


def render(scene: Scene, path: Path, store: AssetStore) -> bytes:
    """Backend entry point: the SDF file's bytes."""
    return sdf_text(scene, path, store).encode("utf-8")


