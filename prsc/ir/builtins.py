"""What the language provides before any file is read: Object's properties, functions, constants."""

from __future__ import annotations

import math

from prsc.errors import Span
from prsc.ir.model import Type

ROOT_CLASS = "Object"
BUILTIN_SPAN = Span("<builtin Object>", 1, 1, 1, 1)  # where Object's defaults are "written"
DENSITY = 500.0  # kg/m^3 of an object that declares no `mass` (docs/language.md section 11)


def default_mass(width: float, length: float, height: float) -> float:
    """The mass of an object that declares no `mass`: DENSITY times its box volume."""
    return DENSITY * (width * length * height)


# Built-in properties and the static types a value for them may have.
PROPERTY_TYPES: dict[str, frozenset[Type]] = {
    "position": frozenset({Type.VECTOR, Type.ORIENTED_POINT}),
    "orientation": frozenset({Type.VECTOR}),  # compat Euler angles Vector3D(yaw, pitch, roll)
    "width": frozenset({Type.SCALAR}),
    "length": frozenset({Type.SCALAR}),
    "height": frozenset({Type.SCALAR}),
    "color": frozenset({Type.STRING, Type.LIST}),
    "allowCollisions": frozenset({Type.BOOL}),
    "static": frozenset({Type.BOOL}),
    "mass": frozenset({Type.SCALAR}),
    "shape": frozenset({Type.STRING}),
    "mesh": frozenset({Type.STRING}),
    "scale": frozenset({Type.SCALAR}),  # mesh file units -> metres, for sizes taken from the mesh
    "collision": frozenset({Type.STRING}),  # a mesh's collision geometry: "hull" or "decomposed"
    "texture": frozenset({Type.STRING}),  # an image on a box, cylinder or sphere
    "upAxis": frozenset({Type.STRING}),  # the mesh file's axis that points up: "+z" (default), "+y", ...
    "model": frozenset({Type.STRING}),
    "tcp": frozenset({Type.STRING}),  # a robot's tool link, body or site (docs/assets.md)
    "camera": frozenset({Type.BOOL}),
    "fovy": frozenset({Type.SCALAR}),
    "resolution": frozenset({Type.LIST}),
    "light": frozenset({Type.BOOL}),  # a light, not a body
    "kind": frozenset({Type.STRING}),  # a light's: "directional" or "spot"
    "intensity": frozenset({Type.SCALAR}),  # a light's colour is multiplied by it
    "cutoff": frozenset({Type.SCALAR}),  # a spot light's half angle of its cone (degrees)
    "castShadow": frozenset({Type.BOOL}),
    # compat aliases, kept as given (the sampler maps them)
    "model_name": frozenset({Type.STRING}),
    "shape_type": frozenset({Type.STRING}),
}

# Object's defaults. Properties without an entry (color, mass, model, static, mesh, ...)
# are absent from ObjectDecl.properties unless set: the sampler applies its own rule
# (mass from density 500 kg/m^3, static from the model, grey colour).
OBJECT_DEFAULTS: tuple[tuple[str, float | str | bool], ...] = (
    ("width", 1.0),
    ("length", 1.0),
    ("height", 1.0),
    ("allowCollisions", False),
    ("shape", "box"),
    ("camera", False),
)

# Properties that specifiers set; never in ObjectDecl.properties.
SPECIFIER_PROPERTIES = ("position", "orientation")

# What a position specifier that erodes by the object's box reads.
BOX_READS = ("width", "length", "height", "orientation")

# Pure math functions: name -> (min args, max args or None for any).
FUNCTIONS: dict[str, tuple[int, int | None]] = {
    "sin": (1, 1),
    "cos": (1, 1),
    "tan": (1, 1),
    "sqrt": (1, 1),
    "abs": (1, 1),
    "min": (1, None),
    "max": (1, None),
    "hypot": (2, 2),
    "atan2": (2, 2),
}

MATH_CONSTANTS: dict[str, float] = {"pi": math.pi, "e": math.e, "tau": math.tau}

DISTRIBUTIONS = ("Range", "Normal", "TruncatedNormal", "Uniform", "Options", "Discrete")
REGIONS = ("Cuboid", "Rectangle3D", "Rect3D", "HalfSpace", "Halfspace", "ConvexPolygon3D",
           "ConvexPolyhedron", "Intersection", "All", "Empty")
VECTORS = ("Vector3D", "V3D")
CONSTRUCTORS = DISTRIBUTIONS + REGIONS + VECTORS

FACE_WORD_GROUPS = (("top", "bottom"), ("front", "back"), ("left", "right"))
DIRECTIONS = ("left", "right", "ahead", "behind", "above", "below")
# How a direction specifier is written before its reference (`left of X`, `behind X`).
DIRECTION_PHRASES = {"left": "left of", "right": "right of", "ahead": "ahead of",
                     "behind": "behind", "above": "above", "below": "below"}
AXES = ("x", "y", "z")

# Python modules a spec might try to import: named in the error instead of "not found".
PYTHON_MODULES = frozenset({"numpy", "scipy", "random", "os", "sys", "subprocess", "torch", "pathlib",
                            "shutil", "json", "time", "itertools", "functools", "collections",
                            "mujoco", "pybullet", "scenic", "probRobScene", "builtins", "io"})


JOINT_PREFIX = "joint "
"""`with joint "NAME" v` sets the property `joint NAME` (a name no `with prop` can spell)."""


def joint_property(joint: str) -> str:
    """The property that holds joint `joint`'s starting value."""
    return JOINT_PREFIX + joint


def joint_name(prop: str) -> str | None:
    """The joint a property sets, or None when it is not a joint value."""
    return prop[len(JOINT_PREFIX):] if prop.startswith(JOINT_PREFIX) else None
