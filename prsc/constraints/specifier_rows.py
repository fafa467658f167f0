"""Position specifiers as labelled rows on the object's centre p (docs/sampling.md, the rows table).

Each function takes the concrete values of one scene and returns a Polytope whose rows
all carry `label`. `support` is the placed object's support function s(n).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from prsc.constraints.polytope_ir import Support
from prsc.constraints.regions import link_face
from prsc.constraints.values import LinkValue, ObjectValue, OrientedPoint, RegionValue, as_position
from prsc.errors import PrscError, Span
from prsc.user_assets.asset_links import link_target_error
from prsc.geometry.container import PROPERTIES as INTERIOR_PROPERTIES, Interior, asset_interior, declared_interior
from prsc.ir.models import model_of
from prsc.geometry.polytope import Polytope

_EYE = np.eye(3)
_UP = np.array([0.0, 0.0, 1.0])

# Direction words -> the side's axis in the target's frame.
DIRECTION_AXES = {
    "left": np.array([-1.0, 0.0, 0.0]),
    "right": np.array([1.0, 0.0, 0.0]),
    "ahead": np.array([0.0, 1.0, 0.0]),
    "behind": np.array([0.0, -1.0, 0.0]),
    "above": np.array([0.0, 0.0, 1.0]),
    "below": np.array([0.0, 0.0, -1.0]),
}


def _point_rows(point: np.ndarray, label: int) -> Polytope:
    """p = point."""
    return Polytope(np.zeros((0, 3)), np.zeros(0), _EYE, np.asarray(point, dtype=float), np.zeros(0, np.int64), np.full(3, label))


def _placed(target: ObjectValue, span: Span | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if target.position is None or target.rotation is None or target.dims is None:
        raise PrscError(f"{target.name} is not placed yet here", span)
    return target.position, target.rotation, np.asarray(target.dims, dtype=float)


def _vector(value: Any, what: str, span: Span | None) -> np.ndarray:
    pos = as_position(value)
    if pos is None:
        raise PrscError(f"{what} must be an object, a face point or a vector", span)
    return np.asarray(pos, dtype=float)


def _scalar(value: Any, what: str, span: Span | None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise PrscError(f"{what} must be a number", span)
    return float(value)


def rows_at(point: Any, label: int, span: Span | None) -> Polytope:
    """`at V`: p = V."""
    return _point_rows(_vector(point, "the point of 'at'", span), label)


def rows_beyond(target: Any, by: Any, origin: Any, label: int, span: Span | None) -> Polytope:
    """`beyond X by d from P`: p = X + d unit(X - P), or a vector d in the frame facing from P to X."""
    x = _vector(target, "the target of 'beyond'", span)
    p = _vector(origin, "the origin of 'beyond'", span)
    if isinstance(by, np.ndarray):
        forward = x - p
        forward = np.array([forward[0], forward[1], 0.0])
        norm = float(np.linalg.norm(forward))
        if not norm > 0:
            raise PrscError("'beyond' with a vector distance needs a horizontal direction from P to X", span)
        y = forward / norm
        xaxis = np.cross(y, _UP)
        return _point_rows(x + by[0] * xaxis + by[1] * y + by[2] * _UP, label)
    d = _scalar(by, "the distance of 'beyond'", span)
    direction = x - p
    norm = float(np.linalg.norm(direction))
    if not norm > 0:
        raise PrscError("'beyond X from P' needs X and P to differ", span)
    return _point_rows(x + d * direction / norm, label)


def rows_in(region: Any, completely: bool, support: Support, label: int, span: Span | None) -> Polytope:
    """`[completely] in R`: p in R, or the whole box in R (erosion of R's inequality rows); in a
    link, on its floor within its walls."""
    if isinstance(region, LinkValue):
        link_target_error(region.label, region.support is not None, region.interior is not None, True, completely, span)
        return _rows_on_surface(link_face(region, region.interior), completely, support, label, span)
    if not isinstance(region, RegionValue):
        raise PrscError("'in' needs a region", span)
    poly = region.poly
    b = poly.b - support(poly.A) if completely and len(poly.b) else poly.b
    return Polytope(poly.A, b, poly.C, poly.d, np.full(len(b), label), np.full(len(poly.d), label))


def rows_on(target: Any, completely: bool, support: Support, label: int, span: Span | None,
            inside_asset: bool = False, inside: bool = False) -> Polytope:
    """`[completely] on X` for an object, a planar region or a point (`inside_asset`: on the
    floor of a container asset that declares no interior, as `completely on` asks; `inside`:
    written `in X`, which needs X to be a container)."""
    if isinstance(target, ObjectValue):
        pos, rot, dims = _placed(target, span)
        interior = interior_of(target, span, inside_asset or inside)
        if interior is not None:
            return _rows_in_container(pos, rot, interior, support, label)
        if inside:
            word = "completely in" if completely else "in"
            raise PrscError(f"`{word} {target.name}` needs a container (a class declaring {', '.join(INTERIOR_PROPERTIES)}, "
                            f"or a container asset), and {target.name} is none: to rest on its top write "
                            f"`{'completely on' if completely else 'on'} {target.name}`, for a solid region `in Cuboid(...)`", span)
        u, v, n = rot[:, 0], rot[:, 1], rot[:, 2]
        top = pos + n * (dims[2] * 0.5)
        s = support(np.stack([n, u, v]))
        su, sv = (s[1], s[2]) if completely else (0.0, 0.0)
        a = np.stack([u, -u, v, -v])
        tu, tv = float(u @ top), float(v @ top)
        b = np.array([tu + dims[0] * 0.5 - su, -tu + dims[0] * 0.5 - su, tv + dims[1] * 0.5 - sv, -tv + dims[1] * 0.5 - sv])
        return Polytope(a, b, n[None, :], np.array([n @ top + s[0]]), np.full(4, label), np.full(1, label))
    if isinstance(target, RegionValue):
        return _rows_on_surface(target, completely, support, label, span)
    if isinstance(target, LinkValue):
        link_target_error(target.label, target.support is not None, target.interior is not None, False, completely, span)
        return _rows_on_surface(link_face(target, target.support), completely, support, label, span)
    point = as_position(target)
    if point is not None:
        return _point_rows(point + _UP * float(support(_UP[None, :])[0]), label)
    raise PrscError("'on' needs an object, a planar region or a point", span)


def interior_of(target: ObjectValue, span: Span | None, inside_asset: bool = False) -> Interior | None:
    """The container interior the object's class declares (docs/language.md, "Containers"), if any;
    with `inside_asset` (for `completely on`), else the interior of the container asset the class uses."""
    if any(k in target.property_fns and k not in target.props for k in INTERIOR_PROPERTIES):
        raise PrscError(f"the interior of {target.name} ({', '.join(INTERIOR_PROPERTIES)}) must be constants", span)
    declared = {k: target.props[k] for k in INTERIOR_PROPERTIES if k in target.props}
    if not declared:
        # A class that declares no interior but is built as a hollow container asset (the
        # original project's model library): `completely on` it means inside it, on the
        # floor the backends build, never on the rim it would fall from. A bare `on` keeps
        # the rim, since its footprint may cross the walls the sampler does not know.
        return asset_interior(model_of(target.props, target.class_name), target.dims) if inside_asset else None  # type: ignore[arg-type]
    try:
        return declared_interior(target.dims, declared)  # type: ignore[arg-type]
    except ValueError as error:
        raise PrscError(f"{target.name}: {error}", span) from None


def _rows_in_container(pos: np.ndarray, rot: np.ndarray, interior: Interior, support: Support, label: int) -> Polytope:
    """On a container, `on` or `completely on`: rest on its floor's top with the footprint inside
    the walls. The walls rise from the floor, so a footprint across one is a collision (docs/language.md,
    guarantees), which the box test cannot see: the container's box holds the object (constraints/container_pairs.py)."""
    u, v, n = rot[:, 0], rot[:, 1], rot[:, 2]
    normals, offsets = interior.edges()
    a = normals[:, :1] * u + normals[:, 1:] * v
    b = a @ pos + offsets - support(a)
    floor = pos + n * interior.floor_top
    rest = float(n @ floor + support(n[None, :])[0])
    return Polytope(a, b, n[None, :], np.array([rest]), np.full(len(b), label), np.full(1, label))


def _rows_on_surface(region: RegionValue, completely: bool, support: Support, label: int, span: Span | None) -> Polytope:
    """On a planar region: rest on the plane, centre projecting inside (footprint inside if completely)."""
    if region.normal is None:
        raise PrscError(f"'on' needs a surface, but this {region.kind} region is solid; use 'in'", span)
    n = region.normal
    poly = region.poly
    # The plane n.x = offset: taken from the equality row parallel to n.
    offset = None
    for c, d in zip(poly.C, poly.d):
        cn = float(c @ n)
        if abs(abs(cn) - np.linalg.norm(c)) > 1e-9 * max(1.0, float(np.linalg.norm(c))):
            raise PrscError("'on' needs a planar region (this intersection is a line or a point)", span)
        if offset is None:
            offset = float(d) / cn
    if offset is None:
        raise PrscError("'on' needs a planar region", span)
    sn = float(support(n[None, :])[0])
    if region.clearance is not None and 2 * sn > region.clearance + 1e-9:
        raise PrscError(f"the object ({2 * sn:.3f} m tall) does not fit under the next board "
                        f"({region.clearance:.3f} m free above this one)", span)
    a = poly.A
    # Project p back onto the plane: p_proj = p - s(n) n, so a.p_proj <= b  <=>  a.p <= b + s(n) a.n.
    b = poly.b + sn * (a @ n)
    if completely and len(b):
        in_plane = a - np.outer(a @ n, n)
        b = b - support(in_plane)
    return Polytope(a, b, n[None, :], np.array([offset + sn]), np.full(len(b), label), np.full(1, label))


def _frame(target: Any, span: Span | None) -> tuple[np.ndarray, np.ndarray]:
    """(point, rotation) of a direction/aligned target: object, face point or vector (world axes)."""
    if isinstance(target, ObjectValue):
        pos, rot, _ = _placed(target, span)
        return pos, rot
    if isinstance(target, OrientedPoint):
        return target.position, target.rotation
    if isinstance(target, np.ndarray) and target.shape == (3,):
        return target, _EYE
    raise PrscError("expected an object, a face point or a vector", span)


def rows_direction(relation: str, target: Any, by: Any, support: Support, label: int, span: Span | None,
                   up_to: Any = None) -> Polytope:
    """`left of X by d` etc.: n.(p - X) >= d + s(n), n the side's axis in X's frame; with
    `by (d, e)` also n.(p - X) <= e + s(n): the gap between the plane and the box lies in [d, e]."""
    point, rot = _frame(target, span)
    n = rot @ DIRECTION_AXES[relation]
    d = 0.0 if by is None else _scalar(by, f"the distance of '{relation}'", span)
    base = float(n @ point) + float(support(n[None, :])[0])
    if up_to is None:
        return Polytope((-n)[None, :], np.array([-(base + d)]), np.zeros((0, 3)), np.zeros(0), np.full(1, label),
                        np.zeros(0, np.int64))
    e = _scalar(up_to, f"the greatest distance of '{relation}'", span)  # e < d: no room (a dead end)
    return Polytope(np.stack([-n, n]), np.array([-(base + d), base + e]), np.zeros((0, 3)), np.zeros(0),
                    np.full(2, label), np.zeros(0, np.int64))


def rows_aligned(target: Any, axis: str, label: int, span: Span | None) -> Polytope:
    """`aligned with X on axis`: p's world coordinate on that axis equals X's."""
    point = _vector(target, "the target of 'aligned with'", span)
    i = "xyz".index(axis)
    return Polytope(np.zeros((0, 3)), np.zeros(0), _EYE[i : i + 1], np.array([point[i]]), np.zeros(0, np.int64), np.full(1, label))
