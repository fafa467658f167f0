"""Concrete values that IR expressions evaluate to within one scene.

Scalars are Python floats, booleans bools, strings str, lists tuples, vectors numpy
arrays of shape (3,), rotations numpy arrays of shape (3, 3) (columns = local axes in
world coordinates). Objects, face points and regions have the classes below.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
from numpy.typing import NDArray

from prsc.errors import PrscError, Span
from prsc.geometry.polytope import Polytope

# A property function takes the scene context (context.py, which holds ObjectValues and so
# sits above this module): typed by what it is, not by importing it.
SceneContext = Any

Vector = NDArray[np.float64]

DIMENSIONS = ("width", "length", "height")  # the properties that size an object's box

# Marks a property whose evaluation is under way (a `self.a` / `self.b` cycle).
_IN_PROGRESS = object()


@dataclass(eq=False)
class ObjectValue:
    """One scene object as far as it is known: properties are evaluated lazily on first use."""

    name: str
    class_name: str
    span: Span
    position: Vector | None = None
    rotation: NDArray[np.float64] | None = None
    dims: tuple[float, float, float] | None = None
    props: dict[str, Any] = field(default_factory=dict)
    # Property name -> closure(ctx) computing it; consulted when a property is first read.
    property_fns: dict[str, Callable[[SceneContext], Any]] = field(default_factory=dict)

    def get(self, prop: str, ctx: SceneContext | None, span: Span | None = None) -> Any:
        """The value of `prop`, evaluating it (once) if needed."""
        if prop == "position":
            if self.position is None:
                raise PrscError(f"the position of {self.name} is not known yet here", span)
            return self.position
        if prop == "orientation":
            if self.rotation is None:
                raise PrscError(f"the orientation of {self.name} is not known yet here", span)
            return self.rotation
        if prop in ("x", "y", "z"):
            return float(self.get("position", ctx, span)["xyz".index(prop)])
        if prop in self.props:
            value = self.props[prop]
            if value is _IN_PROGRESS:
                raise PrscError(f"property {prop!r} of {self.name} depends on itself", span)
            return value
        fn = self.property_fns.get(prop)
        if fn is None:
            raise PrscError(f"{self.name} has no property {prop!r}", span)
        if ctx is None:
            raise PrscError(f"property {prop!r} of {self.name} is not known yet here", span)
        self.props[prop] = _IN_PROGRESS
        try:
            value = fn(ctx)
        except BaseException:
            self.props.pop(prop, None)
            raise
        self.props[prop] = value
        return value

    def half_extents(self) -> Vector:
        """Half of (width, length, height)."""
        assert self.dims is not None
        return np.array(self.dims) * 0.5


@dataclass(frozen=True, eq=False)
class OrientedPoint:
    """A face point: a position carrying the orientation of the object it belongs to."""

    position: Vector
    rotation: NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class RegionValue:
    """A concrete convex region: its H-representation plus what `on`/`completely` need.

    `normal` is set for planar regions (kind rectangle, polygon, or an intersection that
    contains one): the unit normal of the plane, pointing up (or along the region's own
    +z when the plane is vertical).
    """

    kind: str
    poly: Polytope
    normal: Vector | None = None
    # A furniture surface's free height above the plane (the next board), None: open above.
    clearance: float | None = None

    @property
    def planar(self) -> bool:
        """Whether the region is (part of) a plane."""
        return self.normal is not None


@dataclass(frozen=True)
class LinkValue:
    """A link of an articulated object placed in the scene (`X.links["NAME"]`): its frame in
    the world and its support surface and interior in that frame (None where it has none)."""

    label: str  # as written: cabinet.links['drawer']
    origin: Vector
    axes: NDArray[np.float64]  # columns: the link's axes in the world
    support: Any  # prsc.geometry.link_surfaces.Face | None: made a region only when used
    interior: Any



def as_position(value: Any) -> Vector | None:
    """The position denoted by a vector, face point or object, else None."""
    if isinstance(value, np.ndarray) and value.shape == (3,):
        return value
    if isinstance(value, OrientedPoint):
        return value.position
    if isinstance(value, ObjectValue):
        return value.position
    return None


def dimension(value: Any, prop: str, obj_name: str, span: Span | None) -> float:
    """An object's width, length or height as a float; a PrscError unless it is a number >= 0."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not value >= 0:
        raise PrscError(f"{prop} of {obj_name} must be a number >= 0, got {value!r}", span)
    return float(value)


def static_dims(props: dict[str, Any]) -> tuple[float, float, float] | None:
    """(width, length, height) from properties known at compile time; None unless all three are."""
    if not all(d in props for d in DIMENSIONS):
        return None
    return (float(props["width"]), float(props["length"]), float(props["height"]))
