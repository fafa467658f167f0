"""Concrete regions from evaluated region-constructor arguments (docs/language.md section 9)."""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from prsc.constraints.values import LinkValue, ObjectValue, RegionValue, as_position
from prsc.errors import PrscError, Span
from prsc.geometry.boxes import Box
from prsc.geometry.furniture_surfaces import ASSET_SURFACES, asset_surfaces
from prsc.geometry.kinematics import chain_pose
from prsc.geometry.link_surfaces import Face, LinkSurfaces
from prsc.geometry.polytope import Polytope, intersect
from prsc.geometry.rotations import compat_euler_to_matrix
from prsc.ir.builtins import joint_property
from prsc.ir.models import model_of

_PLANAR_TOL = 1e-9


def rotation_of(value: Any, span: Span | None) -> np.ndarray:
    """A rotation matrix from a compat Euler vector (docs/language.md, `with orientation`) or a matrix."""
    arr = np.asarray(value, dtype=float) if not isinstance(value, (str, bool)) else None
    if arr is not None and arr.shape == (3, 3):
        return arr
    if arr is not None and arr.shape == (3,):
        return compat_euler_to_matrix(float(arr[0]), float(arr[1]), float(arr[2]))
    raise PrscError("expected an orientation (Vector3D of yaw, pitch, roll)", span)


def up_normal(normal: np.ndarray) -> np.ndarray:
    """The unit normal flipped to point up (kept as is for a vertical plane)."""
    n = normal / np.linalg.norm(normal)
    return -n if n[2] < -_PLANAR_TOL else n


def _vector(value: Any, what: str, span: Span | None) -> np.ndarray:
    pos = as_position(value)
    if pos is None:
        raise PrscError(f"{what} must be a vector", span)
    return np.asarray(pos, dtype=float)


def _positive(value: Any, what: str, span: Span | None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise PrscError(f"{what} must be a number", span)
    if not value >= 0:
        raise PrscError(f"{what} must be >= 0, got {value}", span)
    return float(value)


def cuboid(position: Any, orientation: Any, width: Any, length: Any, height: Any, span: Span | None) -> RegionValue:
    """The solid box `Cuboid(position, orientation, width, length, height)`."""
    dims = [_positive(v, n, span) for v, n in ((width, "width"), (length, "length"), (height, "height"))]
    box = Box.from_dimensions(_vector(position, "the cuboid's position", span), rotation_of(orientation, span), dims)
    return RegionValue("cuboid", Polytope.from_box(box))


def rectangle(position: Any, orientation: Any, width: Any, length: Any, span: Span | None) -> RegionValue:
    """The planar rectangle `Rectangle3D(width, length, origin, orientation)`."""
    rot = rotation_of(orientation, span)
    poly = Polytope.from_rectangle(
        _vector(position, "the rectangle's origin", span), rot, _positive(width, "width", span), _positive(length, "length", span)
    )
    return RegionValue("rectangle", poly, up_normal(rot[:, 2]))


def halfspace(point: Any, normal: Any, dist: Any, span: Span | None) -> RegionValue:
    """{x : 0 <= n.(x - point) [<= dist]}: the side the normal points into (compat).

    The original bounded its half-spaces by `dist` along the normal; a dist of 0 (the
    default) means unbounded.
    """
    p = _vector(point, "the half-space's point", span)
    n = _vector(normal, "the half-space's normal", span)
    norm = float(np.linalg.norm(n))
    if not norm > 0:
        raise PrscError("the half-space's normal is zero", span)
    n = n / norm
    d = _positive(dist, "the half-space's distance", span)
    rows = [-n]
    offsets = [-(n @ p)]
    if d > 0:
        rows.append(n)
        offsets.append(n @ p + d)
    return RegionValue("halfspace", Polytope.from_rows(np.array(rows), np.array(offsets)))


def _points(vertices: Any, what: str, span: Span | None) -> np.ndarray:
    if not isinstance(vertices, (tuple, list)):
        raise PrscError(f"{what} needs a list of vertices", span)
    return np.array([_vector(v, "a vertex", span) for v in vertices], dtype=float).reshape(-1, 3)


def polygon(vertices: Any, span: Span | None) -> RegionValue:
    """`ConvexPolygon3D([v1, v2, ...])`: the convex hull of coplanar vertices."""
    pts = _points(vertices, "ConvexPolygon3D", span)
    if len(pts) < 3:
        raise PrscError("ConvexPolygon3D needs at least 3 vertices", span)
    centre = pts.mean(axis=0)
    _, sing, vt = np.linalg.svd(pts - centre)
    scale = max(float(sing[0]), 1e-12)
    if sing[1] <= 1e-9 * scale:
        raise PrscError("ConvexPolygon3D's vertices are collinear", span)
    if sing[2] > 1e-7 * scale:
        raise PrscError("ConvexPolygon3D's vertices are not coplanar", span)
    normal = up_normal(vt[2])
    u = vt[0]
    v = np.cross(normal, u)
    flat = np.stack([(pts - centre) @ u, (pts - centre) @ v], axis=1)
    from scipy.spatial import ConvexHull  # here, not at the top: 0.2 s of every CLI start-up

    hull = ConvexHull(flat)
    # hull.equations rows: [a_u, a_v, c] with a . y + c <= 0 inside.
    a2 = hull.equations[:, :2]
    c2 = hull.equations[:, 2]
    a3 = a2[:, :1] * u + a2[:, 1:] * v
    b3 = -c2 + a3 @ centre
    poly = Polytope.from_rows(a3, b3, C=normal[None, :], d=[normal @ centre])
    return RegionValue("polygon", poly, normal)


def polyhedron(vertices: Any, span: Span | None) -> RegionValue:
    """`ConvexPolyhedron([v1, ...])`: the convex hull of the vertices."""
    pts = _points(vertices, "ConvexPolyhedron", span)
    from scipy.spatial import ConvexHull, QhullError  # here, not at the top: 0.2 s of every CLI start-up

    try:
        hull = ConvexHull(pts)
    except (QhullError, ValueError) as error:
        raise PrscError("ConvexPolyhedron's vertices do not span a solid (need 4 or more, not coplanar)", span) from error
    return RegionValue("polyhedron", Polytope.from_rows(hull.equations[:, :3], -hull.equations[:, 3]))


def everything() -> RegionValue:
    """`All()`."""
    return RegionValue("all", Polytope.everything())


def empty() -> RegionValue:
    """`Empty()`: the row 0 . p <= -1."""
    return RegionValue("empty", Polytope.from_rows(np.zeros((1, 3)), [-1.0]))


def intersection(regions: Sequence[Any], span: Span | None) -> RegionValue:
    """`Intersection(r1, r2, ...)`: all rows together; planar if any member is."""
    members = list(regions)
    if not members or not all(isinstance(r, RegionValue) for r in members):
        raise PrscError("Intersection needs one or more regions", span)
    normal = next((r.normal for r in members if r.normal is not None), None)
    return RegionValue("intersection", intersect(*(r.poly for r in members)), normal)


def surface(target: Any, name: str, index: Any, span: Span | None) -> RegionValue:
    """`X.name[k]`: support surface k of X's furniture asset, as a rectangle moved to X's pose
    (prsc.geometry.furniture_surfaces, the numbers the asset recipe builds)."""
    if not isinstance(target, ObjectValue) or target.position is None or target.rotation is None or target.dims is None:
        raise PrscError(f"{name}[...] needs a placed object", span)
    model = model_of(target.props, target.class_name)
    found = asset_surfaces(model, name, target.dims)
    if found is None:
        known = [f"{m}: {', '.join(s)}" for m, s in ASSET_SURFACES.items()]
        raise PrscError(f"{target.name}'s model {model!r} has no support surfaces {name!r} "
                        f"(known: {'; '.join(known)})", span)
    if isinstance(index, bool) or not isinstance(index, (int, float)) or index != int(index) \
            or not 0 <= index < len(found):
        shown = f"{index:g}" if isinstance(index, float) else repr(index)
        raise PrscError(f"{target.name}.{name} has {len(found)} surfaces, indexed 0 to {len(found) - 1} "
                        f"(0 the lowest), not {shown}", span)
    board = found[int(index)]
    rot = target.rotation
    centre = target.position + rot @ np.asarray(board.centre)
    poly = Polytope.from_rectangle(centre, rot, board.width, board.length)
    return RegionValue("rectangle", poly, up_normal(rot[:, 2]), board.clearance)


def link(target: Any, label: str, chain: Any, surfaces: LinkSurfaces, root_offset: Sequence[float], ctx: Any,
         span: Span | None) -> LinkValue:
    """`X.links["NAME"]`: the link's frame at X's pose and X's joint values in this scene, with
    its support surface and interior (`chain` is the link's prsc.user_assets.asset_links.AssetLink)."""
    if not isinstance(target, ObjectValue) or target.position is None or target.rotation is None:
        raise PrscError(f"{label} needs a placed object", span)
    joints = {j.name: float(target.get(joint_property(j.name), ctx, span)) for step in chain.chain for j in step.joints}
    position, rotation = chain_pose(chain.chain, joints)
    position = position - np.asarray(chain.root_position)  # from the root body's origin, as the box is
    origin = target.position + target.rotation @ (np.asarray(root_offset) + position)
    axes = target.rotation @ rotation
    return LinkValue(label, origin, axes, surfaces.support, surfaces.interior)


def link_face(link: LinkValue, face: Face) -> RegionValue:
    """A face of a placed link as a world rectangle (a planar region)."""
    width, length = face.size
    poly = Polytope.from_rectangle(link.origin + link.axes @ np.asarray(face.centre), link.axes, width, length)
    return RegionValue("rectangle", poly, up_normal(link.axes[:, 2]))
