"""MJCF backend: one self-contained MuJoCo model per scene, built with mujoco.MjSpec.

Layout (names the runner relies on):
- a body per object named after it, at the scene pose (box centre); a free object has a
  free joint of the same name; geoms are named `<object>/<part>`;
- an articulated asset (a user's URDF or MJCF, or a library arm: prsc/assets/articulated.py)
  attached with prefix `<object>/`, its root body where the file puts it in its box (so
  `r1/<root>`, `r1/<joint>`, `r1/tcp`, actuators `r1/<joint>` and the library's own). The offset is the root body's own `pos`, not a `<frame>`: Drake's MuJoCo parser skips frames, and with them the whole robot;
- a camera object: a camera named after the object looking along the object's +y
  (image up = its +z) with the object's fovy and resolution;
- a keyframe `home`: free bodies at their scene poses, robot joints at the scene's `joints`
  (the asset's home where the spec sets none), position servos holding them.

Speed: a scene's MJCF is one template per scene topology (which bodies, parts, robots,
cameras: backends/scene_structure.py), built once per process with MjSpec and cached, with a slot for
every number that changes from scene to scene (`_stamps`: poses, sizes, masses, colours,
file paths, the `home` key, the model name). A scene then costs only its numbers,
formatted exactly (MjSpec writes 6 significant digits; the slots hold full precision).
The robot's MJCF fragment (bodies, assets, actuators, equalities) is built once per
process and prefix by MjSpec.attach and spliced into the template.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from prsc.user_assets.joint_servos import is_position_servo
from prsc.user_assets.asset_files import COLLISION_GROUP  # COLLISION_GROUP: collision-only geoms, hidden when drawn
from prsc.assets.articulated import RobotModel
from prsc.assets.simulation import set_simulation_options
from prsc.backends.inertia import PRIMITIVES
from prsc.backends.bodies import CAMERA_QUAT_NEG_Z, Body, light_directions, resolve_bodies
from prsc.backends.numbers import num, nums
from prsc.backends.scene import GROUND_HALF_SIZE, Scene
from prsc.backends.scene_structure import scene_structure, template_key
from prsc.backends.store import AssetStore, relative_path
from prsc.backends.xmltext import element_text, placeholder, serialise
from prsc.errors import PrscError

FRICTION = (1.0, 0.005, 0.0001)  # sliding, torsional, rolling
SOLREF = (0.01, 1.0)  # stiffer than the default 0.02 so resting objects sink < 1 mm
TEXTURED_RGBA = (1.0, 1.0, 1.0, 1.0)  # a textured part shows its image's own colours
CONDIM_FREE = 4  # torsional friction: a held or resting object does not spin in place
SECTION_ORDER = (
    "compiler", "option", "size", "visual", "statistic", "default", "asset", "worldbody",
    "contact", "equality", "tendon", "actuator", "sensor", "keyframe",
)


@dataclass
class RobotFragment:
    """The MJCF of one attached robot as serialised text per section, ready to splice."""

    sections: dict[str, str]  # section tag -> its child elements as XML text
    base: str  # the robot's root body as XML text, without a position of its own
    joints: tuple[str, ...]  # the robot's joints in qpos order (unprefixed)
    servo_joints: tuple[str | None, ...]  # per actuator: the joint it holds as a position servo, or None

    def base_at(self, position: str) -> str:
        """The root body's XML text with `pos="position"` (text) in its parent body."""
        head, tail = self.base.split(">", 1)
        return f'{head} pos="{position}">{tail}'

    def home(self, robot: RobotModel, joints: dict[str, float]) -> tuple[list[str], list[str]]:
        """The `home` key's qpos and ctrl of this robot at the scene's joint values: each
        position servo holds its joint there, other actuators start at 0."""
        values = robot.home(joints)
        qpos = [num(values[name]) for name in self.joints]
        ctrl = [num(values[name]) if name is not None else "0" for name in self.servo_joints]
        return qpos, ctrl


def _options(spec) -> None:
    """Simulation options shared by scenes and robot fragments (so attach does not conflict)."""
    spec.compiler.degree = False
    set_simulation_options(spec.option)


@lru_cache(maxsize=32)
def _robot_fragment_xml(robot: RobotModel, prefix: str) -> tuple[str, tuple[str, ...], tuple[str | None, ...]]:
    """XML of a model holding only the robot attached with `prefix`, its joints in qpos
    order and the joint each actuator servoes (built once per process)."""
    import mujoco

    holder = mujoco.MjSpec()
    _options(holder)
    child = robot.mjcf_spec()
    frame = holder.worldbody.add_frame()
    frame.attach_body(child.body(robot.root), prefix, "")
    model = holder.compile()
    joints = tuple(model.joint(j).name[len(prefix):] for j in range(model.njnt))
    servo_joints = []
    for a in range(model.nu):
        servo = int(model.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_JOINT) and is_position_servo(model, a)
        servo_joints.append(joints[model.actuator_trnid[a, 0]] if servo else None)
    return holder.to_xml(), joints, tuple(servo_joints)


def _robot_fragment(robot: RobotModel, prefix: str, store: AssetStore, folder: Path) -> RobotFragment:
    """The robot fragment with mesh files pointing into the store, relative to `folder`."""
    xml, joints, servo_joints = _robot_fragment_xml(robot, prefix)
    root = ET.fromstring(xml)
    sections: dict[str, str] = {}
    for section in root:
        if section.tag in ("compiler", "option", "size", "worldbody", "keyframe", "visual", "statistic"):
            continue
        for element in section:
            if element.get("file"):
                element.set("file", relative_path(store.robot_file(robot.key, element.get("file")), folder))
        sections[section.tag] = "\n".join(element_text(e) for e in section)
    base = next(root.find("worldbody").iter("body"))
    base.attrib.pop("pos", None)  # the mount places it
    return RobotFragment(sections, element_text(base), joints, servo_joints)


_fragment_cache: dict[tuple[RobotModel, str, str, str], RobotFragment] = {}


def robot_fragment(robot: RobotModel, prefix: str, store: AssetStore, folder: Path) -> RobotFragment:
    """Cached robot fragment for one prefix and output folder."""
    key = (robot, prefix, str(store.root), str(folder))
    if key not in _fragment_cache:
        _fragment_cache[key] = _robot_fragment(robot, prefix, store, folder)
    return _fragment_cache[key]


def _geom_type(shape: str):
    import mujoco

    return {
        "box": mujoco.mjtGeom.mjGEOM_BOX,
        "cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER,
        "sphere": mujoco.mjtGeom.mjGEOM_SPHERE,
        "mesh": mujoco.mjtGeom.mjGEOM_MESH,
    }[shape]


def primitive_geom_sizes(shape: str, extents: np.ndarray) -> np.ndarray:
    """MuJoCo `size` rows (half extents; radius and half height; radius) of box, cylinder or sphere
    parts of full `extents` (rows x y z)."""
    extents = np.asarray(extents, dtype=float).reshape(-1, 3)
    if shape == "box":
        return extents / 2
    cylinder = shape == "cylinder"
    radius = (np.minimum(extents[:, 0], extents[:, 1]) if cylinder else extents.min(axis=1)) / 2  # Part.radius
    sizes = np.zeros_like(extents)
    sizes[:, 0] = radius
    if cylinder:
        sizes[:, 1] = extents[:, 2] / 2
    return sizes


def geom_size(part) -> tuple[float, ...]:
    """A part's MuJoCo `size` (`primitive_geom_sizes`; a mesh's is its own)."""
    if part.shape not in PRIMITIVES:
        return (0.0, 0.0, 0.0)
    return tuple(float(v) for v in primitive_geom_sizes(part.shape, part.size)[0])


def _check_masses(scene: Scene, bodies: tuple[Body, ...]) -> None:
    """MuJoCo refuses a free body without mass or inertia when it compiles: say which and why."""
    import mujoco

    for body in bodies:
        inertial = body.inertial
        if not body.fixed and min(inertial.mass, *inertial.diagonal) <= mujoco.mjMINVAL:
            raise PrscError(
                f"scene {scene.index}: object {body.obj.name!r} cannot move in MuJoCo: its mass ({inertial.mass:.3g} kg) "
                f"and principal inertia (smallest {min(inertial.diagonal):.3g} kg m^2) must exceed "
                f"{mujoco.mjMINVAL:g}; check its size and mass, or make it static"
            )


def _map_roles() -> dict:
    """MuJoCo's material role of each PBR map a textured mesh part may carry."""
    import mujoco

    return {"normal": mujoco.mjtTextureRole.mjTEXROLE_NORMAL, "orm": mujoco.mjtTextureRole.mjTEXROLE_ORM}


def geom_rgba(obj, part) -> tuple[float, ...]:
    """A part's MuJoCo `rgba`: white under an image (it shows its own colours), else the object's colour."""
    return TEXTURED_RGBA if part.texture is not None else tuple(obj.color)


def light_attributes(body: Body) -> dict[str, str]:
    """A light object's MJCF `light` attributes that change from scene to scene, as text: a light of
    the world body where the object is, shining along the object's +y."""
    light = body.light
    assert light is not None
    return {"pos": nums(body.obj.position), "dir": nums(light_directions(body.obj.quaternion)[0]),
            "diffuse": nums(light.diffuse), "cutoff": num(light.cutoff),
            "castshadow": "true" if light.cast_shadow else "false"}


def _stamps(bodies: tuple[Body, ...], folder: Path) -> dict[tuple[str, str], dict[str, str]]:
    """Every number (and file path) of the scene's own elements that changes from scene to
    scene, exactly, by (tag, element name) and attribute: the text that fills a template's
    slots (numbers need no escaping; paths are escaped here)."""
    exact: dict[tuple[str, str], dict[str, str]] = {}
    for body in bodies:
        obj, inertial = body.obj, body.inertial
        if body.light is not None:
            exact[("light", obj.name)] = light_attributes(body)
            continue
        exact[("body", obj.name)] = {"pos": nums(obj.position), "quat": nums(obj.quaternion)}
        exact[("inertial", obj.name)] = {
            "pos": nums(inertial.com), "quat": nums(inertial.principal),
            "mass": num(inertial.mass), "diaginertia": nums(inertial.diagonal),
        }
        for part in body.parts:
            gname = f"{obj.name}/{part.name}"
            stamp = {"pos": nums(part.position), "quat": nums(part.quaternion), "rgba": nums(geom_rgba(obj, part))}
            if part.shape == "mesh":
                exact[("mesh", gname)] = {"file": _attribute(relative_path(part.mesh, folder)), "scale": nums(part.size)}
            else:
                stamp["size"] = nums(geom_size(part)[: {"box": 3, "cylinder": 2, "sphere": 1}[part.shape]])
            if part.texture is not None:
                exact[("texture", gname)] = {"file": _attribute(relative_path(part.texture, folder))}
            for role, image in part.maps:
                exact[("texture", f"{gname}/{role}")] = {"file": _attribute(relative_path(image, folder))}
            exact[("geom", gname)] = stamp
        if body.camera is not None:
            exact[("camera", obj.name)] = {"quat": nums(CAMERA_QUAT_NEG_Z), "fovy": num(body.camera.fovy)}
    return exact


def _scene_spec(scene: Scene, bodies: tuple[Body, ...]):
    """The scene without robots as an MjSpec (its numbers are stamped exactly afterwards)."""
    import mujoco

    spec = mujoco.MjSpec()
    _options(spec)
    width = max([640] + [b.camera.width for b in bodies if b.camera])
    height = max([480] + [b.camera.height for b in bodies if b.camera])
    spec.visual.global_.offwidth = width
    spec.visual.global_.offheight = height
    # Dim headlight plus one sun from above: colours stay readable (no saturation).
    spec.visual.headlight.ambient = [0.3, 0.3, 0.3]
    spec.visual.headlight.diffuse = [0.3, 0.3, 0.3]
    spec.visual.headlight.specular = [0.0, 0.0, 0.0]
    spec.add_texture(
        name="prsc_grid", type=mujoco.mjtTexture.mjTEXTURE_2D, builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER,
        rgb1=[0.82, 0.82, 0.80], rgb2=[0.72, 0.72, 0.70], width=256, height=256,
    )
    # texuniform: the checker repeats per metre (8 per 2 m) on the finite ground, as on an infinite one.
    material = spec.add_material(name="prsc_grid", texrepeat=[8, 8], texuniform=True, reflectance=0.0)
    material.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "prsc_grid"
    spec.worldbody.add_light(
        name="prsc_sun", type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL, pos=[0, 0, 4], dir=[0.2, 0.3, -1],
        diffuse=[0.6, 0.6, 0.6], specular=[0.1, 0.1, 0.1], castshadow=False,
    )
    if scene.ground:
        spec.worldbody.add_geom(
            name="ground", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[GROUND_HALF_SIZE, GROUND_HALF_SIZE, 0.05],
            material="prsc_grid", friction=list(FRICTION), solref=list(SOLREF),
        )
    for body in bodies:
        obj = body.obj
        if body.light is not None:
            kind = {"directional": mujoco.mjtLightType.mjLIGHT_DIRECTIONAL, "spot": mujoco.mjtLightType.mjLIGHT_SPOT}
            spec.worldbody.add_light(
                name=obj.name, type=kind[body.light.kind], pos=list(obj.position),
                dir=list(light_directions(obj.quaternion)[0]), diffuse=list(body.light.diffuse),
                specular=[0.1, 0.1, 0.1], cutoff=body.light.cutoff, castshadow=body.light.cast_shadow,
            )
            continue
        b = spec.worldbody.add_body(name=obj.name, pos=list(obj.position), quat=list(obj.quaternion))
        if not body.fixed:
            b.add_freejoint(name=obj.name)
        # Every body gets an explicit inertial (a robot's is its near-massless mount's).
        inertial = body.inertial
        b.explicitinertial = True
        b.mass = inertial.mass
        b.ipos = list(inertial.com)
        b.iquat = list(inertial.principal)
        b.inertia = list(inertial.diagonal)
        for part in body.parts:
            gname = f"{obj.name}/{part.name}"
            kwargs = dict(
                name=gname, type=_geom_type(part.shape), pos=list(part.position), quat=list(part.quaternion),
                rgba=list(geom_rgba(obj, part)), friction=list(FRICTION), solref=list(SOLREF),
                condim=CONDIM_FREE if not body.fixed else 3,
            )
            if part.shape == "mesh":
                # Absolute here (to_xml compiles and would resolve against the cwd),
                # relative to the output file in the written XML.
                spec.add_mesh(name=gname, file=str(part.mesh), scale=list(part.size))
                kwargs["meshname"] = gname
            else:
                kwargs["size"] = list(geom_size(part))
            if part.texture is not None:
                # A mesh reads its image through its UVs; `with texture` shows it on each face of a box.
                kind = mujoco.mjtTexture.mjTEXTURE_2D if part.shape == "mesh" else mujoco.mjtTexture.mjTEXTURE_CUBE
                spec.add_texture(name=gname, type=kind, file=str(part.texture),
                                 colorspace=mujoco.mjtColorSpace.mjCOLORSPACE_AUTO)  # a PNG says its own
                material = spec.add_material(name=gname)
                material.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = gname
                roles = _map_roles() if part.maps else {}
                for role, image in part.maps:  # data, not colour: read linearly
                    spec.add_texture(name=f"{gname}/{role}", type=kind, file=image,
                                     colorspace=mujoco.mjtColorSpace.mjCOLORSPACE_LINEAR)
                    material.textures[roles[role]] = f"{gname}/{role}"
                kwargs["material"] = gname  # unmodulated: rgba white
            if not part.collides:
                kwargs.update(contype=0, conaffinity=0)
            if not part.visible:
                kwargs["group"] = COLLISION_GROUP
            b.add_geom(**kwargs)
        if body.camera is not None:
            b.add_camera(
                name=obj.name, quat=list(CAMERA_QUAT_NEG_Z), fovy=body.camera.fovy,
                resolution=[body.camera.width, body.camera.height],
            )
    return spec


def _slot(number: int) -> str:
    """The mark of slot `number` in a template's text (private-use characters: never in XML prsc writes)."""
    return f"\ue000{number}\ue000"


def _stamp(root: ET.Element, exact: dict[tuple[str, str], dict[str, str]], slots: list[tuple]) -> None:
    """Replace every number `exact` holds by a slot, each attribute in `exact`'s order after the
    element's others: the text is the same whatever values MjSpec left out as defaults."""

    def mark(element: ET.Element, key: tuple[str, str]) -> None:
        for attr in exact[key]:
            element.attrib.pop(attr, None)
        for attr in exact[key]:
            element.set(attr, _slot(len(slots)))
            slots.append(("exact", key, attr))

    for tag in ("mesh", "texture", "light"):
        for element in root.iter(tag):
            if (tag, element.get("name", "")) in exact:
                mark(element, (tag, element.get("name", "")))
    for body in root.iter("body"):
        name = body.get("name")
        if ("body", name) not in exact:
            continue
        mark(body, ("body", name))
        for child in body:
            key = (child.tag, child.get("name", name) if child.tag != "inertial" else name)
            if key in exact:
                mark(child, key)


def _section(root: ET.Element, tag: str) -> ET.Element:
    """The top-level section `tag`, created in canonical order when missing."""
    found = root.find(tag)
    if found is not None:
        return found
    element = ET.Element(tag)
    rank = SECTION_ORDER.index(tag)
    position = len(root)
    for i, child in enumerate(root):
        if child.tag in SECTION_ORDER and SECTION_ORDER.index(child.tag) > rank:
            position = i
            break
    root.insert(position, element)
    return element


@dataclass(frozen=True)
class _Template:
    """One scene topology's MJCF text with slots for what changes from scene to scene."""

    texts: tuple[str, ...]  # the text around the slots (one more than slots)
    slots: tuple[tuple, ...]  # ("exact", key, attr) | ("model",) | ("qpos",) | ("ctrl",) | ("mount", body name)

    def fill(self, values: dict[tuple, str]) -> str:
        """The MJCF text with every slot filled."""
        out = [self.texts[0]]
        for slot, text in zip(self.slots, self.texts[1:]):
            out.append(values[slot])
            out.append(text)
        return "".join(out)


_ATTRIBUTE_ESCAPES = str.maketrans({"&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "\n": "&#10;",
                                    "\r": "&#13;", "\t": "&#09;"})
_templates: dict[tuple, _Template] = {}
TEMPLATES_KEPT = 64  # topologies a process keeps (a spec has one, or a few with random models)


def _attribute(text: str) -> str:
    """`text` as an XML attribute value (a file path may hold any of these)."""
    return text.translate(_ATTRIBUTE_ESCAPES)


def _template(scene: Scene, bodies: tuple[Body, ...], store: AssetStore, folder: Path,
              exact: dict[tuple[str, str], dict[str, str]]) -> _Template:
    """The template of this scene's topology, built with MjSpec once (cached per process)."""
    key = template_key(scene_structure(scene, bodies), store.root, folder)
    if key in _templates:
        return _templates[key]
    root = ET.fromstring(_scene_spec(scene, bodies).to_xml())
    slots: list[tuple] = []
    root.set("model", _slot(len(slots)))
    slots.append(("model",))
    _stamp(root, exact, slots)
    pieces: list[str] = []
    holders = {b.get("name"): b for b in root.find("worldbody").findall("body")}
    qpos = ctrl = False
    for body in bodies:
        qpos = qpos or not body.fixed
        if body.robot is None:
            continue
        fragment = robot_fragment(body.robot, f"{body.obj.name}/", store, folder)
        placeholder(holders[body.obj.name], pieces, fragment.base_at(_slot(len(slots))))
        slots.append(("mount", body.obj.name))
        for tag, text in fragment.sections.items():
            # Robot default classes become subclasses of the scene's top-level default.
            if text:
                placeholder(_section(root, tag), pieces, text)
        qpos = qpos or bool(fragment.joints)
        ctrl = ctrl or bool(fragment.servo_joints)
    if qpos or ctrl:
        home = ET.SubElement(_section(root, "keyframe"), "key", name="home")
        for name, present in (("qpos", qpos), ("ctrl", ctrl)):
            if present:
                home.set(name, _slot(len(slots)))
                slots.append((name,))
    size = root.find("size")
    if size is not None:
        root.remove(size)  # nkey etc. are derived by the compiler
    # The marks survive serialisation; the slots fill in the order the text holds them.
    texts = (serialise(root, pieces) + "\n").split("\ue000")
    order = [slots[int(number)] for number in texts[1::2]]
    template = _Template(tuple(texts[0::2]), tuple(order))
    if len(_templates) >= TEMPLATES_KEPT:
        _templates.pop(next(iter(_templates)))
    _templates[key] = template
    return template


def mjcf_xml(scene: Scene, path: Path, store: AssetStore) -> str:
    """The MJCF text of a scene to be written at `path` (mesh paths are relative to it)."""
    folder = Path(path).parent
    bodies = resolve_bodies(scene, store)
    _check_masses(scene, bodies)
    exact = _stamps(bodies, folder)
    template = _template(scene, bodies, store, folder, exact)
    values: dict[tuple, str] = {("model",): f"prsc_scene_{scene.index}"}
    for key, attrs in exact.items():
        for attr, value in attrs.items():
            values[("exact", key, attr)] = value
    qpos: list[str] = []
    ctrl: list[str] = []
    for body in bodies:
        obj = body.obj
        if not body.fixed:
            qpos += [num(v) for v in obj.position] + [num(v) for v in obj.quaternion]
        if body.robot is None:
            continue
        fragment = robot_fragment(body.robot, f"{obj.name}/", store, folder)
        values[("mount", obj.name)] = nums(body.mount_position)
        robot_qpos, robot_ctrl = fragment.home(body.robot, obj.joints)
        qpos += robot_qpos
        ctrl += robot_ctrl
    values[("qpos",)], values[("ctrl",)] = " ".join(qpos), " ".join(ctrl)
    return template.fill(values)


def render(scene: Scene, path: Path, store: AssetStore) -> bytes:
    """Backend entry point: the MJCF file's bytes."""
    return mjcf_xml(scene, path, store).encode("utf-8")
