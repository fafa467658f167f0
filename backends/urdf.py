"""URDF backend: a bundle folder per scene, one URDF per object plus `scene.json`.

pybullet turns a URDF `floating` joint into a fixed one, so a whole scene cannot be one
URDF with free objects. Instead each object is its own URDF whose root link is named after
the object and sits at the object's box centre; `scene.json` lists, per object, the
arguments of `pybullet.loadURDF(urdf, base_position, base_orientation_xyzw,
useFixedBase=use_fixed_base)` (the pose is the root link frame: the scene pose exactly).

A robot (an asset from a file, the library's arms too) is its URDF under a root link `<object>`
with a fixed joint `<object>_mount` to its root link where the file puts it in the box, yawed
by the asset's base_yaw so the arm reaches along the object's +y. A camera object carries its
intrinsics in `scene.json` and a Gazebo `<sensor type="camera">` extension.
"""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from functools import lru_cache
from pathlib import Path

from prsc.backends.bodies import Body, light_directions, resolve_bodies
from prsc.backends.gazebo_camera import camera_sensor_body
from prsc.backends.inertia import Inertial
from prsc.backends.numbers import num, nums
from prsc.backends.scene import GROUND_HALF_SIZE, Scene
from prsc.assets.articulated import RobotModel, check_robot_name
from prsc.backends.store import AssetStore, relative_path
from prsc.backends.xmltext import element_text, placeholder, serialise
from prsc.geometry.rotations import quat_to_rpy

GROUND_THICKNESS = 0.1


def _origin(parent: ET.Element, xyz, quat=None, rpy=None) -> None:
    if rpy is None:
        rpy = quat_to_rpy(quat) if quat is not None else (0.0, 0.0, 0.0)
    ET.SubElement(parent, "origin", xyz=nums(xyz), rpy=nums(rpy))


def _inertial(link: ET.Element, inertial: Inertial) -> None:
    element = ET.SubElement(link, "inertial")
    _origin(element, inertial.com)
    ET.SubElement(element, "mass", value=num(inertial.mass))
    t = inertial.tensor
    ET.SubElement(
        element, "inertia",
        ixx=num(t[0][0]), ixy=num(t[0][1]), ixz=num(t[0][2]), iyy=num(t[1][1]), iyz=num(t[1][2]), izz=num(t[2][2]),
    )


def _geometry(parent: ET.Element, part, folder: Path) -> None:
    geometry = ET.SubElement(parent, "geometry")
    if part.shape == "box":
        ET.SubElement(geometry, "box", size=nums(part.size))
    elif part.shape == "cylinder":
        ET.SubElement(geometry, "cylinder", radius=num(part.radius), length=num(part.size[2]))
    elif part.shape == "sphere":
        ET.SubElement(geometry, "sphere", radius=num(part.radius))
    else:
        ET.SubElement(geometry, "mesh", filename=relative_path(part.mesh, folder), scale=nums(part.size))


def _parts_urdf(body: Body, folder: Path) -> ET.Element:
    """A one-link URDF of a rigid object made of parts."""
    obj = body.obj
    robot = ET.Element("robot", name=obj.name)
    material = ET.SubElement(robot, "material", name=f"{obj.name}_color")
    ET.SubElement(material, "color", rgba=nums(obj.color))
    link = ET.SubElement(robot, "link", name=obj.name)
    _inertial(link, body.inertial)
    for part in (p for p in body.parts if p.visible):
        visual = ET.SubElement(link, "visual", name=part.name)
        _origin(visual, part.position, part.quaternion)
        _geometry(visual, part, folder)
        if part.texture is None:
            ET.SubElement(visual, "material", name=f"{obj.name}_color")
        else:  # white, so the image is not tinted; the OBJ's own MTL names the same image
            textured = ET.SubElement(visual, "material", name=f"{obj.name}_{part.name}_texture")
            ET.SubElement(textured, "color", rgba="1 1 1 1")
            ET.SubElement(textured, "texture", filename=relative_path(part.texture, folder))
    for part in body.parts:
        if not part.collides:
            continue
        collision = ET.SubElement(link, "collision", name=part.name)
        _origin(collision, part.position, part.quaternion)
        _geometry(collision, part, folder)
    if body.camera is not None:
        _gazebo_camera(robot, body)
    return robot


def _gazebo_camera(robot: ET.Element, body: Body) -> None:
    """Gazebo's camera sensor extension on the object link."""
    gazebo = ET.SubElement(robot, "gazebo", reference=body.name)
    camera_sensor_body(ET.SubElement(gazebo, "sensor", type="camera", name=body.name), body.camera)


@lru_cache(maxsize=32)
def _robot_body_text(robot: RobotModel, store_root: str, store_from_bundle: str) -> tuple[str, ...]:
    """The robot URDF's top-level elements as text, mesh paths pointing into the store.

    Keyed by the store's path relative to the bundle folder, which every scene's bundle
    shares, so the text is built once per process.
    """
    store = AssetStore(store_root)
    root = ET.parse(robot.urdf).getroot()
    for mesh in root.iter("mesh"):
        source = robot.urdf.parent / mesh.get("filename")  # relative to the URDF (or absolute)
        inside = relative_path(store.robot_file(robot.key, source), store.root)
        mesh.set("filename", f"{store_from_bundle}/{inside}")
    return ("\n".join(element_text(child) for child in root),)


@lru_cache(maxsize=32)
def robot_root_link(robot: RobotModel) -> str:
    """Name of the root link of a robot's URDF."""
    template = ET.parse(robot.urdf).getroot()
    children = {j.find("child").get("link") for j in template.findall("joint")}
    return next(l.get("name") for l in template.findall("link") if l.get("name") not in children)


def _robot_urdf(body: Body, store: AssetStore, folder: Path) -> str:
    """The robot's URDF under a mount link named after the object at its box centre."""
    assert body.robot is not None
    robot = ET.Element("robot", name=body.name)
    check_robot_name(body.robot, body.name)
    mount = ET.SubElement(robot, "link", name=body.name)
    _inertial(mount, body.inertial)
    joint = ET.SubElement(robot, "joint", name=f"{body.name}_mount", type="fixed")
    _origin(joint, body.mount_position, rpy=(0.0, 0.0, body.robot.base_yaw))
    ET.SubElement(joint, "parent", link=body.name)
    ET.SubElement(joint, "child", link=robot_root_link(body.robot))
    pieces: list[str] = []
    for text in _robot_body_text(body.robot, str(store.root), relative_path(store.root, folder)):
        placeholder(robot, pieces, text)
    return '<?xml version="1.0"?>\n' + serialise(robot, pieces) + "\n"


def _ground_urdf() -> ET.Element:
    """A fixed slab whose top face is the plane z = 0 (URDF has no infinite plane)."""
    robot = ET.Element("robot", name="ground")
    link = ET.SubElement(robot, "link", name="ground")
    inertial = ET.SubElement(link, "inertial")
    _origin(inertial, (0.0, 0.0, 0.0))
    ET.SubElement(inertial, "mass", value="0")
    ET.SubElement(inertial, "inertia", ixx="0", ixy="0", ixz="0", iyy="0", iyz="0", izz="0")
    for tag in ("visual", "collision"):
        element = ET.SubElement(link, tag, name="slab")
        _origin(element, (0.0, 0.0, -GROUND_THICKNESS / 2))
        geometry = ET.SubElement(element, "geometry")
        ET.SubElement(geometry, "box", size=nums((2 * GROUND_HALF_SIZE, 2 * GROUND_HALF_SIZE, GROUND_THICKNESS)))
        if tag == "visual":
            material = ET.SubElement(element, "material", name="ground")
            ET.SubElement(material, "color", rgba="0.8 0.8 0.78 1")
    return robot


def _text(robot: ET.Element) -> str:
    ET.indent(robot, space="  ")
    return '<?xml version="1.0"?>\n' + ET.tostring(robot, encoding="unicode") + "\n"


def xyzw(quat) -> list[float]:
    """A w x y z quaternion in pybullet's x y z w order."""
    w, x, y, z = quat
    return [x, y, z, w]


def urdf_bundle(scene: Scene, folder: Path, store: AssetStore) -> dict[str, str]:
    """The bundle's files (name -> text) for a bundle folder that will live at `folder`."""
    folder = Path(folder)
    bodies = resolve_bodies(scene, store)
    files: dict[str, str] = {}
    entries = []
    lights = []
    for body in bodies:
        obj = body.obj
        if body.light is not None:
            # URDF has no lights: the bundle's metadata holds them, for the loader's renderer.
            lights.append({
                "name": obj.name, "kind": body.light.kind, "position": list(obj.position),
                "direction": light_directions(obj.quaternion)[0].tolist(), "color": list(body.light.color),
                "intensity": body.light.intensity, "cutoff_degrees": body.light.cutoff,
                "cast_shadow": body.light.cast_shadow,
            })
            continue
        filename = f"{obj.name}.urdf"
        files[filename] = _robot_urdf(body, store, folder) if body.robot else _text(_parts_urdf(body, folder))
        camera = None
        if body.camera is not None:
            camera = {
                "fovy": body.camera.fovy,
                "resolution": [body.camera.width, body.camera.height],
                "forward": [0.0, 1.0, 0.0],
                "up": [0.0, 0.0, 1.0],
            }
        entries.append(
            {
                "name": obj.name,
                "urdf": filename,
                "base_position": list(obj.position),
                "base_orientation_xyzw": xyzw(obj.quaternion),
                "use_fixed_base": body.fixed,
                "robot": body.robot.key if body.robot else None,
                # Where each joint starts (URDF has no initial positions; pybullet loads at 0).
                "joints": body.robot.home(body.obj.joints) if body.robot else None,
                "camera": camera,
            }
        )
    ground = None
    if scene.ground:
        name = "ground.urdf"
        while name in files:
            name = "_" + name
        files[name] = _text(_ground_urdf())
        ground = {"urdf": name, "base_position": [0.0, 0.0, 0.0], "base_orientation_xyzw": [0.0, 0.0, 0.0, 1.0], "use_fixed_base": True}
    manifest = {
        "format": "prsc-urdf-bundle",
        "version": 1,
        "spec": scene.spec,
        "seed": scene.seed,
        "index": scene.index,
        "gravity": [0.0, 0.0, -9.81],
        "ground": ground,
        "objects": entries,
        "lights": lights,
    }
    files["scene.json"] = json.dumps(manifest, indent=1) + "\n"
    return files


def render(scene: Scene, path: Path, store: AssetStore) -> dict[str, bytes]:
    """Backend entry point: the bundle folder's files (relative name -> bytes)."""
    return {name: text.encode("utf-8") for name, text in urdf_bundle(scene, path, store).items()}

