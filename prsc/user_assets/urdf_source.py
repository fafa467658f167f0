"""Reading the user's URDF (docs/assets.md): its XML (undeclared prefixes declared), xacro
refused at its line, `package://` and relative mesh paths resolved, meshes MuJoCo cannot
decode converted, and ROS's `world` link dropped. prsc/user_assets/asset_files.py makes models of it."""

from __future__ import annotations

import os
import re
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Sequence

from prsc.user_assets.asset_inertia import drop_invalid_inertias
from prsc.errors import PrscError
from prsc.user_assets.mesh_paths import MUJOCO_MESHES, obj_copy


def _package_path(uri: str, urdf: Path, folders: Sequence[str]) -> str:
    """The file a `package://NAME/rest` names: folder NAME beside the URDF or in an ancestor,
    then in the --include folders."""
    name, _, rest = uri[len("package://"):].partition("/")
    for base in (urdf.parent, *urdf.parent.parents, *map(Path, folders)):
        if (base / name).is_dir():
            return str(base / name / rest)
    raise PrscError(f"{urdf.name}: {uri!r} does not resolve: no folder {name!r} beside the URDF, "
                    "in its parent folders or in the --include folders")


def mesh_file(filename: str, urdf: Path, folders: Sequence[str]) -> str:
    """The absolute path of the mesh a URDF's `<mesh filename>` names (`package://`, `file://`
    or relative to the URDF's folder)."""
    if filename.startswith("package://"):
        filename = _package_path(filename, urdf, folders)
    elif filename.startswith("file://"):
        filename = filename[len("file://"):]
    return str((urdf.parent / filename).resolve())


def _refuse_xacro(root: ET.Element, path: Path) -> None:
    """A URDF that still holds xacro (`$(arg x)`, `${expr}`: husky.urdf's IMU) is refused at the
    first such value, with its line: MuJoCo would only say "bad format in attribute"."""
    for element in root.iter():
        for key, value in element.attrib.items():
            if "$(" in value or "${" in value:
                text = path.read_text(errors="replace")
                at = text.find(value)
                line = f" line {text.count(chr(10), 0, at) + 1}," if at >= 0 else ""
                raise PrscError(f"{path.name}:{line} <{element.tag} {key}=\"{value}\"> is a xacro expression, not a value; "
                                "expand the file with xacro first (`xacro robot.urdf.xacro > robot.urdf`)")


def parse_urdf(path: Path) -> ET.Element:
    """The URDF's root element. A prefix the file uses without declaring it (Drake's
    `drake:acceleration`, which MuJoCo and pybullet ignore) is declared, as those readers
    never ask: XML would refuse the file."""
    try:
        return ET.parse(path).getroot()
    except OSError as error:
        raise PrscError(f"cannot read URDF {path.name}: {error}") from None
    except ET.ParseError as error:
        if "unbound prefix" not in str(error):
            raise PrscError(f"cannot read URDF {path.name}: {error}") from None
    text = path.read_text(encoding="utf-8", errors="replace")
    used = set(re.findall(r"[<\s/]([A-Za-z_][\w.-]*):[A-Za-z_]", text)) - {"xml", "xmlns", "http", "https", "package", "file"}
    declared = set(re.findall(r"xmlns:([A-Za-z_][\w.-]*)\s*=", text))
    missing = " ".join(f'xmlns:{prefix}="urn:prsc:undeclared:{prefix}"' for prefix in sorted(used - declared))
    try:
        return ET.fromstring(re.sub(r"<robot\b", f"<robot {missing}", text, count=1))
    except ET.ParseError as error:
        raise PrscError(f"cannot read URDF {path.name}: {error}") from None


def urdf_tree(path: Path, folders: Sequence[str], converted: Path) -> ET.Element:
    """The URDF's root element with every mesh path absolute (`package://` resolved), meshes
    MuJoCo cannot decode replaced by OBJ copies in the folder `converted`."""
    root = parse_urdf(path)
    if root.tag != "robot":
        raise PrscError(f"{path.name} is not a URDF (its root element is <{root.tag}>, not <robot>)")
    _refuse_xacro(root, path)
    parents = {child: parent for parent in root.iter() for child in parent}
    for mesh in root.iter("mesh"):
        filename = mesh_file(mesh.get("filename", ""), path, folders)
        if not os.path.isfile(filename):
            raise PrscError(f"{path.name}: mesh {mesh.get('filename')!r} not found ({filename})")
        if Path(filename).suffix.lower() not in MUJOCO_MESHES:
            geometry = parents.get(mesh)
            element = parents.get(geometry) if geometry is not None else None
            filename = _converted_mesh(element if element is not None and element.tag == "visual" else None,
                                       filename, path, converted)
        mesh.set("filename", filename)
    drop_invalid_inertias(root, path)
    # A root link named "world" fixed to one child is ROS's way of saying "fixed base";
    # prsc mounts the asset itself, so the child is the root in every format.
    world = [j for j in root.findall("joint") if j.find("parent") is not None and j.find("parent").get("link") == "world"]
    if len(world) == 1 and world[0].get("type") == "fixed":
        root.remove(world[0])
        for link in root.findall("link"):
            if link.get("name") == "world":
                root.remove(link)
    return root


def _converted_mesh(visual: ET.Element | None, filename: str, path: Path, converted: Path) -> str:
    """An OBJ copy of a mesh MuJoCo cannot decode (mesh_paths.obj_copy), its colour given to
    the visual that names it when the URDF gives that visual none (ROS's COLLADA visuals)."""
    try:
        copy, colour = obj_copy(filename, converted)
    except PrscError as error:
        raise PrscError(f"{path.name}: {error}") from None
    if visual is not None and colour is not None and visual.find("material") is None:
        material = ET.SubElement(visual, "material", name=f"prsc_{Path(filename).stem}")
        ET.SubElement(material, "color", rgba=" ".join(repr(round(v, 4)) for v in colour))
    return copy
