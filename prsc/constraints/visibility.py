"""`visible from C`: the object's box inside camera C's view frustum, as exact rows.

A box lies in a convex polytope exactly when every row holds at the box's support point:
a . p + s(a) <= b (the same erosion as `completely in`). docs/language.md, "`visible from C`".
`not visible from C` is the complement: these rows are then a cell the sampler subtracts from
the object's region (ObjectPlan.exclusions), exactly, by free-space decomposition.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from prsc.constraints.support import Support
from prsc.constraints.values import ObjectValue
from prsc.errors import PrscError, Span
from prsc.geometry.frustum import DEFAULT_FAR, DEFAULT_FOVY, DEFAULT_RESOLUTION, Frustum, frustum
from prsc.geometry.polytope import Polytope
from prsc.ir.models import model_of


def _number(props: dict[str, Any], name: str, default: float, owner: str, span: Span | None) -> float:
    value = props.get(name, default)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
        raise PrscError(f"{name} of camera {owner} must be a number > 0, not {value!r}", span)
    return float(value)


def camera_frustum(camera: ObjectValue, span: Span | None) -> Frustum:
    """The view frustum of a camera object: its fovy, resolution and far (or the defaults);
    the near plane is the front face of its box."""
    if camera.dims is None:
        raise PrscError(f"{camera.name} is not placed yet here", span)
    props = camera.props
    fovy = _number(props, "fovy", DEFAULT_FOVY, camera.name, span)
    if not fovy < 180:
        raise PrscError(f"fovy of camera {camera.name} must be below 180 degrees, not {fovy}", span)
    resolution = props.get("resolution", DEFAULT_RESOLUTION)
    if not isinstance(resolution, (tuple, list)) or len(resolution) != 2 \
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0 for v in resolution):
        raise PrscError(f"resolution of camera {camera.name} must be [width, height], not {resolution!r}", span)
    near = camera.dims[1] / 2
    far = _number(props, "far", DEFAULT_FAR, camera.name, span)
    if not far > near:
        raise PrscError(f"far of camera {camera.name} ({far} m) must lie beyond its box's front ({near} m)", span)
    return frustum(near, far, fovy, (float(resolution[0]), float(resolution[1])))


def rows_visible(camera: Any, support: Support, label: int, span: Span | None, phrase: str = "visible from") -> Polytope:
    """`visible from C`: a . p <= b - s(a) for each of the frustum's six planes.

    For `not visible from C` (`phrase`) the same rows are the cell the centre must stay out of.
    """
    if not isinstance(camera, ObjectValue):
        raise PrscError(f"'{phrase}' needs a camera object", span)
    if not (camera.props.get("camera") or model_of(camera.props, camera.class_name) == "camera"):
        raise PrscError(f"'{phrase}' needs a camera (a class with `camera: True`, as tabletop's Camera), "
                        f"and {camera.name} is a {camera.class_name}", span)
    if camera.position is None or camera.rotation is None:
        raise PrscError(f"{camera.name} is not placed yet here", span)
    a, b = camera_frustum(camera, span).world_rows(camera.position, camera.rotation)
    b = b - support(a)
    return Polytope(a, b, np.zeros((0, 3)), np.zeros(0), np.full(len(b), label), np.zeros(0, np.int64))
