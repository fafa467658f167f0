"""The scene JSON (format `prsc-scene`, version 1) as typed, validated, immutable records."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping

from prsc.backends.names import element_names
from prsc.errors import PrscError
from prsc.limits import mass_problem, size_problem

SHAPES = ("box", "cylinder", "sphere", "mesh")


@dataclass(frozen=True)
class CameraSpec:
    """Intrinsics of a camera object: vertical field of view (degrees) and image size."""

    fovy: float
    width: int
    height: int


LIGHT_KINDS = ("directional", "spot")
GROUND_HALF_SIZE = 10.0
"""Metres: half the edge of the ground in every format. Finite, so that a MuJoCo render context's
grid of the ground does not depend on stat.extent and a renderer kept across scenes is never made
again (docs/learning.md, "Renderers kept across resets"); a MuJoCo plane collides as an infinite
one whatever its size. Not larger: a plane counts in stat.extent with a tenth of its size."""


@dataclass(frozen=True)
class LightSpec:
    """A light object: it shines along its local +y from its position."""

    kind: str  # "directional" | "spot"
    color: tuple[float, float, float]  # the object's colour (RGB)
    intensity: float
    cutoff: float  # a spot's half angle (degrees)
    cast_shadow: bool

    @property
    def diffuse(self) -> tuple[float, float, float]:
        """Its colour times its intensity (MuJoCo's `diffuse`)."""
        return tuple(self.intensity * c for c in self.color)  # type: ignore[return-value]


@dataclass(frozen=True)
class SceneObject:
    """One object of a scene: its box (centre pose and size) and physical properties."""

    name: str
    cls: str
    position: tuple[float, float, float]
    quaternion: tuple[float, float, float, float]  # w x y z, unit norm
    dimensions: tuple[float, float, float]  # width (x), length (y), height (z)
    static: bool
    mass: float
    color: tuple[float, float, float, float]
    shape: str
    model: str | None
    camera: CameraSpec | None
    properties: Mapping[str, Any]
    label: str = ""  # the user's name (scene JSON); `name` is its element name (prsc.backends.names)
    joints: Mapping[str, float] = field(default_factory=dict)  # an asset's starting joint values (docs/assets.md)
    light: LightSpec | None = None  # a light, not a body


@dataclass(frozen=True)
class Scene:
    """A sampled scene: where it came from and its objects."""

    spec: str
    seed: int
    index: int
    ground: bool
    objects: tuple[SceneObject, ...]
    raw: Mapping[str, Any]


def _fail(where: str, message: str) -> PrscError:
    return PrscError(f"scene JSON: {where}: {message}")


def _floats(value: Any, count: int, where: str) -> tuple[float, ...]:
    """A list of `count` finite numbers."""
    # The common case first (every scene the sampler writes): exact ints and floats only.
    if type(value) in (list, tuple) and len(value) == count and all(type(item) in (float, int) for item in value):
        out = tuple(map(float, value))
        if all(map(math.isfinite, out)):
            return out
    if not isinstance(value, (list, tuple)) or len(value) != count:
        raise _fail(where, f"expected a list of {count} numbers, got {value!r}")
    for item in value:
        if isinstance(item, bool) or not isinstance(item, (int, float)) or not math.isfinite(item):
            raise _fail(where, f"expected finite numbers, got {value!r}")
    return tuple(float(item) for item in value)


def unit_quaternion(value: Any, where: str) -> tuple[float, float, float, float]:
    """A w x y z quaternion of norm 1 (within 1e-6), normalised exactly as every backend reads it."""
    quat = _floats(value, 4, where)
    norm = math.sqrt(sum(q * q for q in quat))
    if abs(norm - 1.0) > 1e-6:
        raise _fail(where, f"expected a unit quaternion (w x y z), norm is {norm}")
    return tuple(q / norm for q in quat)  # type: ignore[return-value]


def scene_position(value: Any, where: str) -> tuple[float, float, float]:
    """A position: three finite numbers."""
    return _floats(value, 3, where)  # type: ignore[return-value]


def _color(value: Any, where: str) -> tuple[float, float, float, float]:
    """An rgba colour in [0, 1]; an rgb triple gets alpha 1."""
    if isinstance(value, (list, tuple)) and len(value) == 3:
        value = list(value) + [1.0]
    rgba = _floats(value, 4, where)
    if any(c < 0.0 or c > 1.0 for c in rgba):
        raise _fail(where, f"colour components must lie in [0, 1], got {list(rgba)}")
    return rgba  # type: ignore[return-value]


def _camera(value: Any, where: str) -> CameraSpec | None:
    if value is None:
        return None
    if not isinstance(value, Mapping):
        raise _fail(where, f"expected null or an object with fovy and resolution, got {value!r}")
    fovy = _floats([value.get("fovy", 60.0)], 1, f"{where}.fovy")[0]
    if not 0.0 < fovy < 180.0:
        raise _fail(f"{where}.fovy", f"must lie in (0, 180) degrees, got {fovy}")
    res = value.get("resolution", [640, 480])
    if (
        not isinstance(res, (list, tuple))
        or len(res) != 2
        or not all(isinstance(v, int) and not isinstance(v, bool) and v > 0 for v in res)
    ):
        raise _fail(f"{where}.resolution", f"expected [width, height] in pixels, got {res!r}")
    return CameraSpec(fovy=fovy, width=int(res[0]), height=int(res[1]))


def _light(properties: Mapping[str, Any], color: tuple[float, ...], where: str) -> LightSpec | None:
    if properties.get("light") is not True:
        return None
    kind = properties.get("kind", "directional")
    if kind not in LIGHT_KINDS:
        raise _fail(f"{where}.properties.kind", f"a light is one of {', '.join(LIGHT_KINDS)}, got {kind!r}")
    intensity = _floats([properties.get("intensity", 1.0)], 1, f"{where}.properties.intensity")[0]
    if intensity < 0.0:
        raise _fail(f"{where}.properties.intensity", f"must not be negative, got {intensity}")
    cutoff = _floats([properties.get("cutoff", 45.0)], 1, f"{where}.properties.cutoff")[0]
    if not 0.0 < cutoff <= 90.0:
        raise _fail(f"{where}.properties.cutoff", f"must lie in (0, 90] degrees, got {cutoff}")
    shadow = properties.get("castShadow", False)
    if not isinstance(shadow, bool):
        raise _fail(f"{where}.properties.castShadow", f"expected true or false, got {shadow!r}")
    return LightSpec(kind, tuple(color[:3]), intensity, cutoff, shadow)  # type: ignore[arg-type]


def object_dimensions(value: Any, where: str) -> tuple[float, float, float]:
    """An object's `dimensions` (width, length, height), validated; `where` names the object."""
    dims = _floats(value, 3, f"{where}.dimensions")
    if any(d <= 0.0 for d in dims):
        raise _fail(f"{where}.dimensions", f"width, length and height must be positive, got {list(dims)}")
    for axis, size in zip(("width", "length", "height"), dims):
        problem = size_problem(size)
        if problem:
            raise _fail(f"{where}.dimensions", f"{axis} {problem}")
    return dims  # type: ignore[return-value]


def object_mass(value: Any, where: str, free: bool) -> float:
    """An object's `mass`, validated (a free body's must be positive); `where` names the object."""
    mass = _floats([value], 1, f"{where}.mass")[0]
    if mass < 0.0:
        raise _fail(f"{where}.mass", f"must not be negative, got {mass}")
    problem = mass_problem(mass)
    if problem:
        raise _fail(f"{where}.mass", problem)
    if free and mass == 0.0:
        raise _fail(f"{where}.mass", "a free body needs a positive mass")
    return mass


def _object(raw: Any, k: int) -> dict[str, Any]:
    """The fields of one scene object (SceneObject's, but its element name), validated."""
    where = f"objects[{k}]"
    if not isinstance(raw, (dict, Mapping)):
        raise _fail(where, "expected an object")
    name = raw.get("name")
    if not isinstance(name, str) or not name or "/" in name or not name.isprintable():
        raise _fail(where, f"invalid object name {name!r}")
    where = f"object {name!r}"
    quat = unit_quaternion(raw.get("quaternion"), f"{where}.quaternion")
    dims = object_dimensions(raw.get("dimensions"), where)
    static = raw.get("static", False)
    if not isinstance(static, bool):
        raise _fail(f"{where}.static", f"expected true or false, got {static!r}")
    shape = raw.get("shape", "box")
    if shape not in SHAPES:
        raise _fail(f"{where}.shape", f"expected one of {', '.join(SHAPES)}, got {shape!r}")
    properties = raw.get("properties") or {}
    if not isinstance(properties, (dict, Mapping)):
        raise _fail(f"{where}.properties", "expected an object")
    if shape == "mesh" and not isinstance(properties.get("mesh"), str):
        raise _fail(f"{where}.properties.mesh", "a mesh-shaped object needs a mesh file path")
    model = raw.get("model")
    if model is not None and not isinstance(model, str):
        raise _fail(f"{where}.model", f"expected a string or null, got {model!r}")
    camera = _camera(raw.get("camera"), f"{where}.camera")
    mass = object_mass(raw.get("mass"), where, free=not static and camera is None)
    joints = raw.get("joints") or {}
    if not isinstance(joints, (dict, Mapping)) or not all(isinstance(k, str) for k in joints):
        raise _fail(f"{where}.joints", "expected an object of joint name -> value")
    joints = {k: _floats([v], 1, f"{where}.joints.{k}")[0] for k, v in joints.items()}
    cls = raw.get("class", "Object")
    color = _color(raw.get("color", [0.7, 0.7, 0.7, 1.0]), f"{where}.color")
    return dict(
        label=name,
        cls=str(cls),
        position=scene_position(raw.get("position"), f"{where}.position"),
        quaternion=quat,
        dimensions=dims,
        static=static,
        mass=mass,
        color=color,
        shape=shape,
        model=model or None,
        camera=camera,
        properties=properties,
        joints=joints,
        light=_light(properties, color, where),
    )


def parse_object(raw: Any, k: int, element: str) -> SceneObject:
    """Object `k` of a scene JSON, validated, whose element name is known (a shared model's reset)."""
    return SceneObject(name=element, **_object(raw, k))


def parse_scene(raw: Mapping[str, Any]) -> Scene:
    """Validate a scene JSON dict and return it as a typed Scene (PrscError if malformed)."""
    if not isinstance(raw, Mapping) or raw.get("format") != "prsc-scene":
        raise _fail("top level", "not a prsc-scene document (missing \"format\": \"prsc-scene\")")
    if raw.get("version") != 1:
        raise _fail("version", f"unsupported version {raw.get('version')!r} (this prsc reads version 1)")
    objects = raw.get("objects")
    if not isinstance(objects, list):
        raise _fail("objects", "expected a list")
    fields = [_object(o, k) for k, o in enumerate(objects)]
    seen: set[str] = set()
    for found in fields:
        if found["label"] in seen:
            raise _fail(f"object {found['label']!r}", "duplicate object name")
        seen.add(found["label"])
    elements = element_names([found["label"] for found in fields])
    parsed = tuple(SceneObject(name=element, **found) for found, element in zip(fields, elements))
    params = raw.get("params") or {}
    if not isinstance(params, Mapping):
        raise _fail("params", f"expected an object, got {params!r}")
    ground = params.get("ground", True)
    if not isinstance(ground, bool):
        raise _fail("params.ground", f"expected true or false, got {ground!r}")
    numbers = {}
    for key in ("seed", "index"):  # both optional; they name files and episodes when present
        value = raw.get(key, 0)
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            raise _fail(key, f"expected a non-negative integer, got {value!r}")
        numbers[key] = value
    return Scene(
        spec=str(raw.get("spec", "")),
        seed=numbers["seed"],
        index=numbers["index"],
        ground=ground,
        objects=parsed,
        raw=raw,
    )
