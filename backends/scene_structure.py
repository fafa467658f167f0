"""A scene's structure: everything of its MuJoCo model that is not a number written per scene.

Two scenes with equal structures compile to models with the same bodies, joints, geoms,
cameras, lights, actuators and array sizes. The MJCF writer (backends/mjcf.py) keeps one
template per structure; the shared model of `scenario.model()` (backends/shared_model.py)
holds every scene whose structure equals its own, and refuses the others, saying why
(`difference`). This module is the one place that decides what "structure" means.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from prsc.assets.articulated import RobotModel
from prsc.backends.bodies import Body
from prsc.backends.scene import Scene


@dataclass(frozen=True)
class PartStructure:
    """One geom: its name, primitive, collision and visibility flags, and whether it shows an image."""

    name: str
    shape: str  # box | cylinder | sphere | mesh
    collides: bool
    visible: bool
    textured: bool  # an image on it: a texture and a material in the model (which image: a number per scene)
    maps: tuple[str, ...]  # roles of its PBR maps (normal, orm)


@dataclass(frozen=True)
class ObjectStructure:
    """One object's body: free or fixed, its parts, its robot file and joints, its camera's resolution."""

    name: str
    fixed: bool
    robot: RobotModel | None
    camera_resolution: tuple[int, int] | None  # (width, height): compiled into the model
    parts: tuple[PartStructure, ...]
    robot_joints: tuple[str, ...]  # the joints the scene sets on a robot (sorted)
    light: str | None  # a light's kind ("directional" | "spot"): a light of the world body, not a body


@dataclass(frozen=True)
class SceneStructure:
    """A scene's structure: its ground plane and its objects in scene order."""

    ground: bool
    objects: tuple[ObjectStructure, ...]


def _part(part) -> PartStructure:
    return PartStructure(part.name, part.shape, part.collides, part.visible, part.texture is not None,
                         tuple(role for role, _ in part.maps))


def scene_structure(scene: Scene, bodies: tuple[Body, ...]) -> SceneStructure:
    """The structure of a scene, from its resolved bodies."""
    return SceneStructure(scene.ground, tuple(
        ObjectStructure(
            name=b.obj.name, fixed=b.fixed, robot=b.robot,
            camera_resolution=None if b.camera is None else (b.camera.width, b.camera.height),
            parts=tuple(_part(p) for p in b.parts),
            robot_joints=tuple(sorted(b.obj.joints)) if b.robot is not None else (),
            light=None if b.light is None else b.light.kind,
        )
        for b in bodies))


def _fixed(flag: bool) -> str:
    return "fixed" if flag else "free"


def _object_difference(old: ObjectStructure, new: ObjectStructure) -> str:
    """Why object `new` does not fit a model built with `old` (same name)."""
    name = new.name
    if old.fixed != new.fixed:
        return f"object {name!r} is {_fixed(new.fixed)} here, {_fixed(old.fixed)} in the model"
    if old.robot != new.robot:
        here = new.robot.key if new.robot else "none"
        there = old.robot.key if old.robot else "none"
        return f"object {name!r} is another robot ({here}) than in the model ({there})"
    if old.camera_resolution != new.camera_resolution:
        return (f"camera {name!r} has the resolution {new.camera_resolution} here, {old.camera_resolution} in the "
                "model (a camera's resolution is compiled into the model)")
    if old.light != new.light:
        return f"object {name!r} is a {new.light or 'body, not a'} light here, a {old.light or 'body, not a'} light in the model"
    shapes_old = [(p.name, p.shape) for p in old.parts]
    shapes_new = [(p.name, p.shape) for p in new.parts]
    if shapes_old != shapes_new:
        return f"object {name!r} has other parts or shapes ({shapes_new}) than in the model ({shapes_old})"
    if old.robot_joints != new.robot_joints:
        return f"robot {name!r} sets the joints {list(new.robot_joints)} here, {list(old.robot_joints)} in the model"
    textured_old = [p.textured for p in old.parts]
    textured_new = [p.textured for p in new.parts]
    if textured_old != textured_new:
        return f"object {name!r} shows an image on other parts ({textured_new}) than in the model ({textured_old})"
    return f"object {name!r}'s parts differ from the model's ({new.parts} vs {old.parts})"


def difference(old: SceneStructure, new: SceneStructure) -> str | None:
    """Why a scene of structure `new` does not fit a model of structure `old`, naming what differs; None when equal."""
    if old == new:
        return None
    if old.ground != new.ground:
        return (f"{'it has' if new.ground else 'it has no'} ground plane, the model {'has' if old.ground else 'has none'} "
                "(param ground)")
    names_old = [o.name for o in old.objects]
    names_new = [o.name for o in new.objects]
    if names_old != names_new:
        return (f"its objects are {', '.join(names_new)}, the model's {', '.join(names_old)} "
                "(another number of objects or other names)")
    for before, after in zip(old.objects, new.objects):
        if before != after:
            return _object_difference(before, after)
    raise AssertionError("unequal structures with equal objects")  # pragma: no cover


def template_key(structure: SceneStructure, store_root: Path, folder: Path) -> tuple:
    """The key of an MJCF template: the structure, and where the file's paths are relative to."""
    return (structure, str(store_root), str(folder))
