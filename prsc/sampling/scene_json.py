"""Scene JSON (`prsc-scene` version 1, docs/scene-json.md) from a sampled scene.

Maps the compat properties: model_name "Camera" -> a camera object, "Tray"/"Table"/... -> lower-case model names; shape_type
'CUBOID' -> "box", 'CYLINDER' -> "cylinder"; colours by name, grey level string or list
-> rgba; mass by default 500 kg/m^3 times the box volume.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from prsc.constraints.values import DIMENSIONS, ObjectValue, OrientedPoint, RegionValue
from prsc.errors import PrscError, Span
from prsc.ir.builtins import DENSITY, joint_name
from prsc.ir.models import model_of
from prsc.geometry.rotations import matrix_to_quat_one
from prsc.limits import mass_fits, mass_problem, size_fits, size_problem

FORMAT = "prsc-scene"
VERSION = 1
# Models fixed in the world unless the spec says `static False`: cameras stay where they were
# sampled, tables are furniture (an arm, read from a file, is fixed by the IR: ir/asset_models.py).
STATIC_MODELS = frozenset({"camera", "table"})
SHAPES = {"cuboid": "box", "box": "box", "cylinder": "cylinder", "sphere": "sphere", "mesh": "mesh"}
DEFAULT_CAMERA = {"fovy": 60.0, "resolution": [640, 480]}
DEFAULT_COLOR = (0.5, 0.5, 0.5, 1.0)

# Properties that become top-level fields (or are consumed by the mapping).
_MAPPED = frozenset(
    {"position", "orientation", "width", "length", "height", "color", "model", "model_name", "shape",
     "shape_type", "static", "mass", "camera", "fovy", "resolution", "allowCollisions"}
)

_NAMED_COLORS: dict[str, tuple[float, float, float]] = {
    "red": (1.0, 0.0, 0.0),
    "green": (0.0, 0.5, 0.0),
    "blue": (0.0, 0.0, 1.0),
    "white": (1.0, 1.0, 1.0),
    "black": (0.0, 0.0, 0.0),
    "brown": (0.55, 0.35, 0.17),
    "purple": (0.5, 0.0, 0.5),
    "yellow": (1.0, 1.0, 0.0),
    "orange": (1.0, 0.65, 0.0),
    "gray": (0.5, 0.5, 0.5),
    "grey": (0.5, 0.5, 0.5),
    "pink": (1.0, 0.75, 0.8),
    "cyan": (0.0, 1.0, 1.0),
    "magenta": (1.0, 0.0, 1.0),
    "r": (1.0, 0.0, 0.0),
    "g": (0.0, 0.5, 0.0),
    "b": (0.0, 0.0, 1.0),
    "c": (0.0, 0.75, 0.75),
    "m": (0.75, 0.0, 0.75),
    "y": (0.75, 0.75, 0.0),
    "k": (0.0, 0.0, 0.0),
    "w": (1.0, 1.0, 1.0),
}

_QUAT_CACHE: dict[bytes, list[float]] = {}


def color_rgba(value: Any, where: str = "") -> list[float]:
    """An rgba list in [0, 1] from a colour name, a grey-level string or [r, g, b(, a)]."""
    if value is None:
        return list(DEFAULT_COLOR)
    if isinstance(value, str):
        text = value.strip().lower()
        if text in _NAMED_COLORS:
            return [*_NAMED_COLORS[text], 1.0]
        try:
            grey = float(text)
        except ValueError:
            grey = None
        if grey is not None:
            if not 0.0 <= grey <= 1.0:
                raise PrscError(f"grey level {value!r} of {where} is not in [0, 1]")
            return [grey, grey, grey, 1.0]
        try:
            from matplotlib.colors import to_rgba  # CSS names and hex codes

            return [float(c) for c in to_rgba(text)]
        except (ImportError, ValueError) as error:
            raise PrscError(f"unknown colour {value!r} of {where}") from error
    if isinstance(value, (tuple, list, np.ndarray)):
        parts = [float(v) for v in value]
        if len(parts) not in (3, 4) or not all(0.0 <= v <= 1.0 for v in parts):
            raise PrscError(f"a colour list of {where} needs 3 or 4 values in [0, 1], got {parts}")
        return parts + [1.0] if len(parts) == 3 else parts
    raise PrscError(f"cannot read {value!r} as the colour of {where}")


def quaternion_wxyz(rotation: np.ndarray) -> list[float]:
    """The rotation as [w, x, y, z] (w >= 0), cached for repeated rotations."""
    key = rotation.tobytes()
    quat = _QUAT_CACHE.get(key)
    if quat is None:
        quat = matrix_to_quat_one(rotation.tolist())
        if len(_QUAT_CACHE) > 4096:
            _QUAT_CACHE.clear()
        _QUAT_CACHE[key] = quat
    return list(quat)


def json_value(value: Any) -> Any:
    """A property value as plain JSON data."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, (int, float, np.floating, np.integer)):
        v = float(value)
        return v if math.isfinite(v) else None
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (tuple, list)):
        return [json_value(v) for v in value]
    if isinstance(value, dict):
        return {str(k): json_value(v) for k, v in value.items()}
    if isinstance(value, ObjectValue):
        return value.name
    if isinstance(value, OrientedPoint):
        return value.position.tolist()
    if isinstance(value, RegionValue):
        return value.kind
    return str(value)


def shape_of(props: dict[str, Any]) -> str:
    """box | cylinder | sphere | mesh from `shape` or the compat `shape_type`."""
    shape = props.get("shape", "box")
    # `shape` defaults to "box" on every object; the compat shape_type only speaks when
    # shape was left at that default.
    if str(shape).strip().lower() == "box" and props.get("shape_type") is not None:
        shape = props["shape_type"]
    text = str(shape).strip().lower()
    if text not in SHAPES:
        raise PrscError(f"unknown shape {shape!r} (box, cylinder, sphere or mesh)")
    return SHAPES[text]


def _camera_json(props: dict[str, Any], name: str) -> dict[str, Any]:
    """The camera intrinsics of an object: fovy in (0, 180) degrees, resolution [w, h] in pixels."""
    fovy = props.get("fovy", DEFAULT_CAMERA["fovy"])
    if isinstance(fovy, bool) or not isinstance(fovy, (int, float)) or not 0.0 < fovy < 180.0:
        raise PrscError(f"fovy of {name} must be an angle in (0, 180) degrees, got {fovy!r}")
    resolution = props.get("resolution", DEFAULT_CAMERA["resolution"])
    if (
        not isinstance(resolution, (tuple, list)) or len(resolution) != 2
        or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and v >= 1 and v == int(v) for v in resolution)
    ):
        raise PrscError(f"resolution of {name} must be [width, height] in whole pixels, got {json_value(resolution)!r}")
    return {"fovy": float(fovy), "resolution": [int(v) for v in resolution]}


def object_json(obj: ObjectValue) -> dict[str, Any]:
    """One object of the scene JSON (a bad property value is an error at the object)."""
    try:
        return _object_json(obj)
    except PrscError as error:
        if error.span is not None or obj.span is None:
            raise
        raise PrscError(error.message, obj.span, error.notes) from None


def _object_json(obj: ObjectValue) -> dict[str, Any]:
    props = obj.props
    assert obj.position is not None and obj.rotation is not None and obj.dims is not None
    model = model_of(props, obj.class_name)
    is_camera = bool(props.get("camera", False)) or model == "camera"
    static = props.get("static")
    if static is None:
        static = is_camera or model in STATIC_MODELS
    w, l, h = obj.dims
    for prop, value in zip(DIMENSIONS, obj.dims):
        problem = size_problem(float(value))
        if problem:
            raise PrscError(f"{prop} of {obj.name} {problem}")
    mass = object_mass(obj.dims, props.get("mass"))
    problem = mass_problem(mass)
    if problem:
        raise PrscError(f"mass of {obj.name} {problem}")
    camera = _camera_json(props, obj.name) if is_camera else None
    extra = {k: json_value(v) for k, v in props.items() if k not in _MAPPED and joint_name(k) is None}
    if props.get("allowCollisions"):
        extra["allowCollisions"] = True
    joints = {joint_name(k): float(v) for k, v in props.items() if joint_name(k) is not None}
    out = {
        "name": obj.name,
        "class": obj.class_name,
        "position": obj.position.tolist(),
        "quaternion": quaternion_wxyz(obj.rotation),
        "dimensions": [float(w), float(l), float(h)],
        "static": bool(static),
        "mass": mass,
        "color": color_rgba(props.get("color"), obj.name),
        "shape": shape_of(props),
        "model": model,
        "camera": camera,
        "properties": extra,
    }
    if joints:  # an asset from a file: every joint's starting value (docs/assets.md)
        out["joints"] = joints
    return out


def scene_json(
    spec: str, seed: int, index: int, params: dict[str, Any], objects: list[ObjectValue],
    templates: list[dict[str, Any] | SizedTemplate | None] | None = None,
    classes: dict[str, list[str]] | None = None,
) -> dict[str, Any]:
    """The whole scene as a JSON-ready dict (templates: per-object output of `object_template` or
    `sized_template`; classes: each object class's ancestors, most derived first)."""
    out_params = {"ground": True}
    out_params.update({k: json_value(v) for k, v in params.items()})
    if templates is None:
        out_objects = [object_json(o) for o in objects]
    else:
        out_objects = [object_json(o) if t is None else t.place(o) if isinstance(t, SizedTemplate) else _from_template(t, o)
                       for o, t in zip(objects, templates)]
    return scene_dict(spec, seed, index, out_params, out_objects, classes if classes is not None else {})


def scene_dict(spec: str, seed: int, index: int, params: dict[str, Any], objects: list[dict[str, Any]],
               classes: dict[str, list[str]]) -> dict[str, Any]:
    """The scene JSON's top level around its parameters and objects (already JSON data)."""
    return {
        "format": FORMAT,
        "version": VERSION,
        "spec": spec,
        "seed": seed,
        "index": index,
        "params": params,
        "objects": objects,
        # Consumers that look objects up by class (the runner's roles) also accept subclasses.
        "classes": classes,
    }


def object_template(name: str, class_name: str, props: dict[str, Any], span: Span | None = None) -> dict[str, Any]:
    """Everything but the pose of an object whose properties are the same in every scene."""
    dims = tuple(float(props[d]) for d in DIMENSIONS)
    stand_in = ObjectValue(name, class_name, span, np.zeros(3), np.eye(3), dims, dict(props))  # type: ignore[arg-type]
    return object_json(stand_in)


@dataclass(frozen=True)
class SizedTemplate:
    """Everything but the pose, size and mass of an object whose other properties are the same in every scene
    (a part of random size): its JSON is `object_json`'s at a fraction of the cost."""

    template: dict[str, Any]
    mass_from_size: bool  # no `mass` given: density times volume, as object_json computes it

    def place(self, obj: ObjectValue) -> dict[str, Any]:
        """The object's JSON (object_json's, with its errors where its size or mass is not valid)."""
        assert obj.position is not None and obj.rotation is not None and obj.dims is not None
        w, l, h = obj.dims
        mass = object_mass(obj.dims, None if self.mass_from_size else self.template["mass"])
        if not (size_fits(w) and size_fits(l) and size_fits(h) and mass_fits(mass)):  # object_json says what is wrong
            return object_json(obj)
        out = placed_template(self.template, obj.position.tolist(), quaternion_wxyz(obj.rotation))
        out["dimensions"] = [float(w), float(l), float(h)]
        out["mass"] = mass
        return out


def sized_template(name: str, class_name: str, props: dict[str, Any], span: Span | None = None) -> SizedTemplate | None:
    """The template of an object whose properties but its size are the same in every scene (`props`: those);
    None where they are not valid (each scene's `object_json` reports it, as for any object)."""
    stand_in = {d: 1.0 for d in DIMENSIONS}
    stand_in.update(props)
    try:
        return SizedTemplate(object_template(name, class_name, stand_in, span), "mass" not in props)
    except PrscError:
        return None


def object_mass(dims, given: Any) -> float:
    """An object's mass: the one given, else DENSITY times the volume of its box."""
    w, l, h = dims
    return DENSITY * w * l * h if given is None else float(given)


def _from_template(template: dict[str, Any], obj: ObjectValue) -> dict[str, Any]:
    return placed_template(template, obj.position.tolist(), quaternion_wxyz(obj.rotation))  # type: ignore[union-attr, arg-type]


def placed_template(template: dict[str, Any], position: list[float], quaternion: list[float]) -> dict[str, Any]:
    """An object's JSON from its template (`object_template`) and its pose."""
    out = dict(template)
    out["position"] = position
    out["quaternion"] = quaternion
    # Fresh containers per scene: a caller may edit one scene without touching the next.
    out["dimensions"] = list(template["dimensions"])
    out["color"] = list(template["color"])
    out["properties"] = dict(template["properties"])
    if "joints" in template:
        out["joints"] = dict(template["joints"])
    if template["camera"] is not None:
        out["camera"] = {"fovy": template["camera"]["fovy"], "resolution": list(template["camera"]["resolution"])}
    return out
