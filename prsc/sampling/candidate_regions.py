"""The regions candidate rounds draw an object's centre from (candidates.py): its whole region
given the objects before it, as the rejection reference draws it (docs/sampling.md,
"Candidate rounds"). Decided once per spec by the candidate plan (candidate_plan.py):
- **fixed**: the same in every candidate (every rule static), drawn by its exact sampler;
- **carried**: one region translated with an earlier object (a camera above the bin), when
  the static rows provably never cut it (the batched sampler's proof, batched.py), or when
  they are too many to cut per candidate (a reach ring's), then tested per candidate;
- **affine**: for an object of fixed size and rotation, rows carried by an earlier object
  and cut by static rows, solved once for the affine set their equalities leave (a point,
  a segment or a polygon per candidate);
- **point**: `at V` with V random, where the object's fixed rows hold;
- **surface**: `[completely] on` a fixed planar region (a shelf's board), with the object's
  own size and yaw: the region's polygon in its plane, shrunk along its edges by the
  footprint's support when `completely`, cut as a rectangle is;
- **rectangle**: `[completely] on`/`in` an earlier object of fixed size (its top face or its
  container floor), shrunk by the footprint's support along its sides when `completely`,
  when the workspace provably holds it; cut by the object's directions and fixed or carried
  rows into a convex polygon (candidate_cuts.py), rows too many to cut tested instead.
Anything else is Unbatchable.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from prsc.constraints.polytope_ir import Rule
from prsc.constraints.specifier_rows import interior_of
from prsc.constraints.values import ObjectValue, RegionValue
from prsc.errors import PrscError
from prsc.geometry.container import Interior
from prsc.geometry.exceptions import EmptyRegionError, UnboundedRegionError
from prsc.geometry.polytope import Polytope
from prsc.geometry.uniform_sampling import UniformSampler
from prsc.ir import model as ir
from prsc.sampling.batch_values import BatchValue, Unbatchable
from prsc.sampling.batched import carried_corners, rows_hold
from prsc.sampling.candidate_cuts import MAX_CUT_ROWS, Cut, Placed, rule_cut, tested_not_cut
from prsc.sampling.candidate_rules import constant_region, constant_value_of
from prsc.sampling.candidate_values import CandidateCompiler
from prsc.sampling.runtime import ObjectRuntime

_RECTANGLE = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]])  # Interior.edges' normals of a box


@dataclass(frozen=True, eq=False)
class AffineRows:
    """A region carried by an anchor at t and cut by static rows, on the affine set its equalities
    leave: p = origin + shift @ t + basis @ z, and the rows on z are a_z z <= b_z + b_t @ t."""

    origin: np.ndarray  # (3,)
    shift: np.ndarray  # (3, 3)
    basis: np.ndarray  # (3, k), orthonormal columns: k = 0, 1 or 2
    a_z: np.ndarray  # (m, k)
    b_z: np.ndarray  # (m,)
    b_t: np.ndarray  # (m, 3)
    residual: np.ndarray  # (e, 3): the equalities' misfit for anchor t is residual @ t + misfit
    misfit: np.ndarray  # (e,)


@dataclass(frozen=True, eq=False)
class Plane:
    """A fixed planar region n.p = offset (n unit) with in-plane rows a.p <= b, and an orthonormal basis of the plane."""

    normal: np.ndarray
    offset: float
    basis: np.ndarray  # (3, 2)
    a: np.ndarray  # (m, 3)
    b: np.ndarray  # (m,)
    completely: bool


@dataclass(frozen=True, eq=False)
class Region:
    """Where a candidate's centre is drawn: its whole region given the objects before it."""

    kind: str  # fixed | carried | rectangle or surface (cut by `cuts`: a convex polygon) | affine | point
    sampler: UniformSampler | None = None  # fixed, carried (about the anchor)
    point: np.ndarray | None = None  # fixed: a single point
    anchor: str | None = None  # carried, rectangle: the object it moves with
    interior: Interior | None = None  # rectangle: the container floor (None: the top face)
    half_size: tuple[float, float] = (0.0, 0.0)  # rectangle: the face's or floor's half width and length
    completely: bool = False  # rectangle: shrunk by the footprint
    cuts: tuple[Cut, ...] = ()  # rectangle: further rows a.p <= b per candidate (`left of tray`, ...)
    affine: AffineRows | None = None  # affine: carried rows and static rows on a point, line or plane
    at: BatchValue | None = None  # point: `at V`, V random
    plane: Plane | None = None  # surface: the plane and its rows
    rows: Polytope | None = None  # point: the fixed rows V must meet
    tested: Polytope | None = None  # carried: static rows each candidate's centre is tested against

    @property
    def uniforms(self) -> int:
        """Uniforms one draw reads."""
        if self.affine is not None:
            return 3
        if self.at is not None:
            return 0
        if self.sampler is not None:
            return self.sampler.dim + 1
        return 3 if self.cuts or self.plane is not None else 2


def object_region(rt: ObjectRuntime, placed: Placed, reach: float, compiler: CandidateCompiler
                  ) -> tuple[Region, np.ndarray, np.ndarray]:
    """The object's region as candidates draw it, and bounds of its centre in every candidate."""
    provider, name = rt.provider, rt.plan.name
    try:
        if provider.mode == "static":
            provider.fixed_bounds()
            prepared = provider.static_prepared
            if prepared is None:
                raise Unbatchable(f"{name}'s region is empty or unbounded")
            return Region("fixed", prepared.sampler, prepared.point), prepared.lo, prepared.hi
        if provider.mode == "anchored" and rt.support is not None:
            try:
                return _carried(rt, placed)
            except Unbatchable:
                return _affine(rt, placed)  # cut by the static rows in some candidates
    except (EmptyRegionError, UnboundedRegionError):
        raise Unbatchable(f"{name}'s region is empty or unbounded") from None
    if provider.point_rule is not None:
        return _point(rt, compiler)
    return _rectangle(rt, placed, reach, compiler)


def _point(rt: ObjectRuntime, compiler: CandidateCompiler) -> tuple[Region, np.ndarray, np.ndarray]:
    """`at V` with V random: the point, where the object's other rows (fixed ones only) hold."""
    provider, name = rt.provider, rt.plan.name
    if any(not rule.static for rule in provider.plan.rules if rule is not provider.point_rule):
        raise Unbatchable(f"{name} is `at` a point and has other rules that change between scenes")
    value = compiler.compile(provider.point_rule.args[0])  # type: ignore[union-attr]
    if not value.vector:
        raise Unbatchable(f"{name}'s `at` is not a point")
    rows = provider.static_rows if provider.static_rows is not None else Polytope.everything()
    return Region("point", at=value, rows=rows), value.lo.copy(), value.hi.copy()


def _carried(rt: ObjectRuntime, placed: Placed) -> tuple[Region, np.ndarray, np.ndarray]:
    """A region translated with an earlier object, which the static rows never cut (batched.carried_corners)."""
    provider, name = rt.provider, rt.plan.name
    anchor = provider.plan.anchor
    provider.fixed_bounds()
    prepared = provider.anchored_prepared
    if prepared is None or prepared.sampler is None or anchor not in placed.bounds:
        raise Unbatchable(f"{name}'s region carried by {anchor} may be cut, or is a point")
    static = provider.static_rows
    carried = carried_corners(prepared.sampler, corners(*placed.bounds[anchor]), static)
    if carried is not None:
        return Region("carried", prepared.sampler, anchor=anchor), carried.min(axis=0), carried.max(axis=0)
    if static is None or len(static.d) or len(static.b) <= MAX_CUT_ROWS:
        raise Unbatchable(f"{name}'s region carried by {anchor} may be cut by its static rows")
    # Rows too many to cut per candidate (a reach ring's): drawn on the carried region, then tested.
    carried = carried_corners(prepared.sampler, corners(*placed.bounds[anchor]), None)
    return Region("carried", prepared.sampler, anchor=anchor, tested=static), carried.min(axis=0), carried.max(axis=0)


def _affine(rt: ObjectRuntime, placed: Placed) -> tuple[Region, np.ndarray, np.ndarray]:
    """Carried rows A (p - t) <= b, C (p - t) = d and static rows A' p <= b', C' p = d' (regions.RegionProvider's
    anchored mode, cut by its static rows), solved for the affine set of the equalities once."""
    provider, name = rt.provider, rt.plan.name
    anchor, carried, static = provider.plan.anchor, provider.plan.anchored_rows, provider.static_rows
    if anchor not in placed.runtimes or carried is None:
        raise Unbatchable(f"{name}'s region carried by {anchor}")
    empty = Polytope.everything()
    static = static if static is not None else empty
    # Equalities on p: C p = d + C t (carried) and C' p = d' (static), i.e. E p = f + G t.
    e = np.vstack([carried.C, static.C])
    f = np.concatenate([carried.d, static.d])
    g = np.vstack([carried.C, np.zeros_like(static.C)])
    if len(e):
        _, sv, vt = np.linalg.svd(e)
        rank = int(np.sum(sv > 1e-9 * max(sv[0], 1.0)))
        pinv = np.linalg.pinv(e)
        origin, shift, basis = pinv @ f, pinv @ g, vt[rank:].T
    else:
        origin, shift, basis = np.zeros(3), np.zeros((3, 3)), np.eye(3)
    if basis.shape[1] > 2:
        raise Unbatchable(f"{name}'s carried region is solid and cut by its static rows")
    if len(carried.b) + len(static.b) > MAX_CUT_ROWS:
        raise Unbatchable(f"{name}'s carried region is cut by {len(static.b)} static rows")
    # Inequalities: A (origin + shift t + B z - t) <= b and A' (origin + shift t + B z) <= b'.
    a = np.vstack([carried.A, static.A])
    b_z = np.concatenate([carried.b - carried.A @ origin, static.b - static.A @ origin])
    b_t = -np.vstack([carried.A @ (shift - np.eye(3)), static.A @ shift])
    residual = e @ shift - g if len(e) else np.zeros((0, 3))
    misfit = e @ origin - f if len(e) else np.zeros(0)
    rows = AffineRows(origin, shift, basis, a @ basis, b_z, b_t, residual, misfit)
    lo_a, hi_a = placed.bounds[anchor]
    try:
        own = provider.fixed_bounds()  # the carried region's bounds about its anchor, when bounded
    except (EmptyRegionError, UnboundedRegionError):
        own = None
    if own is None:
        if not len(static.b):
            raise Unbatchable(f"{name}'s carried region is unbounded")
        lo, hi = _static_bounds(static)
    else:
        lo, hi = lo_a + own[0], hi_a + own[1]
    return Region("affine", anchor=anchor, affine=rows), lo, hi


def _static_bounds(rows: Polytope) -> tuple[np.ndarray, np.ndarray]:
    """Bounds of a polytope's points (a box around it), or Unbatchable when it is unbounded."""
    from prsc.sampling.prepared import prepare

    try:
        prepared = prepare(rows)
    except (EmptyRegionError, UnboundedRegionError):
        raise Unbatchable("a region that is empty or unbounded") from None
    return prepared.lo, prepared.hi


def _rectangle(rt: ObjectRuntime, placed: Placed, reach: float, compiler: CandidateCompiler
               ) -> tuple[Region, np.ndarray, np.ndarray]:
    """`[completely] on`/`in` an earlier object of fixed size, inside the workspace, cut by the
    object's other rules (directions, fixed or carried rows) into a convex polygon."""
    name = rt.plan.name
    surfaces = [r for r in rt.plan.rules if r.kind == "on"]
    if len(surfaces) != 1:
        kinds = sorted({r.kind for r in rt.plan.rules})
        raise Unbatchable(f"{name}'s region ({', '.join(kinds)}) is not on one object")
    cuts = tuple(rule_cut(r, rt, placed, compiler) for r in rt.plan.rules
                 if r.kind not in ("on", "workspace", "require") and not tested_not_cut(r))
    rule = surfaces[0]
    target = rule.args[0]
    if isinstance(target, ir.SurfaceRef):
        return _surface(rt, rule, reach, cuts)
    if not isinstance(target, ir.ObjectRef) or target.name not in placed.runtimes:
        raise Unbatchable(f"{name} rests on something other than an object placed before it")
    carrier = placed.runtimes[target.name]
    if carrier.dims is None:
        raise Unbatchable(f"{name} rests on {target.name}, whose size changes between scenes")
    interior = _interior(carrier, rule)
    if interior is not None:
        normals, offsets = interior.edges()
        if normals.shape != _RECTANGLE.shape or not np.array_equal(normals, _RECTANGLE) or offsets[0] != offsets[1] \
                or offsets[2] != offsets[3]:
            raise Unbatchable(f"{name} rests in a container whose floor is not a centred rectangle")
        half = (float(offsets[0]), float(offsets[2]))
    else:
        half = (carrier.dims[0] / 2, carrier.dims[1] / 2)
    # In a container the walls keep the footprint inside them, `on` as `completely on` (specifier_rows).
    completely = bool(rule.option("completely")) or interior is not None
    lift = interior.floor_top if interior is not None else carrier.dims[2] / 2
    # The object's box lies in this prism on the face, in the carrier's frame (beyond its sides
    # by up to its reach unless `completely`); the centre in the same prism.
    over = 0.0 if completely else reach
    prism = corners(np.array([-half[0] - over, -half[1] - over, lift]), np.array([half[0] + over, half[1] + over, lift + 2 * reach]))
    lo_c, hi_c = placed.bounds[target.name]
    if carrier.rotation is not None:
        offsets = prism @ carrier.rotation.T
        lo, hi = lo_c + offsets.min(axis=0), hi_c + offsets.max(axis=0)
    else:
        radius = float(np.linalg.norm(prism, axis=1).max())
        lo, hi = lo_c - radius, hi_c + radius
    for workspace in (r for r in rt.plan.rules if r.kind == "workspace"):
        if not rows_hold(constant_region(workspace), corners(lo, hi)):
            raise Unbatchable(f"{name}'s region may be cut by the workspace")
    return Region("rectangle", anchor=target.name, interior=interior, half_size=half,
                  completely=completely, cuts=cuts), lo, hi


def _surface(rt: ObjectRuntime, rule: Rule, reach: float, cuts: tuple[Cut, ...]) -> tuple[Region, np.ndarray, np.ndarray]:
    """`[completely] on` a fixed planar region (a shelf's board): its polygon in the plane, shrunk by the
    footprint's support along each edge when `completely` (specifiers._rows_on_surface)."""
    name = rt.plan.name
    value = constant_value_of(rule)
    if not isinstance(value, RegionValue) or value.normal is None:
        raise Unbatchable(f"{name} rests on a region that is not a fixed plane")
    normal = np.asarray(value.normal, dtype=float)
    poly = value.poly
    planes = [float(d) / float(c @ normal) for c, d in zip(poly.C, poly.d) if abs(abs(float(c @ normal)) - np.linalg.norm(c)) <= 1e-9]
    if len(planes) != len(poly.d) or not planes or not np.isclose(np.linalg.norm(normal), 1.0):
        raise Unbatchable(f"{name} rests on a region that is not one plane")
    if value.clearance is not None and 2 * reach > value.clearance:
        raise Unbatchable(f"{name} may not fit under the next board")  # the scalar sampler explains it
    try:
        lo, hi = _static_bounds(poly)
    except Unbatchable:
        raise Unbatchable(f"{name} rests on an unbounded plane") from None
    for workspace in (r for r in rt.plan.rules if r.kind == "workspace"):
        if not rows_hold(constant_region(workspace), corners(lo - 2 * reach, hi + 2 * reach)):
            raise Unbatchable(f"{name}'s region may be cut by the workspace")
    basis = np.linalg.svd(normal[None, :])[2][1:].T  # (3, 2): orthonormal, in the plane
    plane = Plane(normal, planes[0], basis, poly.A, poly.b, bool(rule.option("completely")))
    return Region("surface", plane=plane, cuts=cuts), lo - 2 * reach, hi + 2 * reach


def _interior(carrier: ObjectRuntime, rule: Rule) -> Interior | None:
    """The container floor `on`/`in` the carrier means (specifiers.rows_on), or None: its top face."""
    plan = carrier.plan
    value = ObjectValue(plan.name, plan.class_name, plan.span, None, None, carrier.dims, dict(plan.static_props), plan.property_fns)
    try:
        interior = interior_of(value, plan.span, bool(rule.option("inside_asset")) or bool(rule.option("inside")))
    except PrscError:
        raise Unbatchable(f"{plan.name}'s interior is not a constant") from None
    if rule.option("inside") and interior is None:
        raise Unbatchable(f"`in {plan.name}`, which is no container")  # the scalar sampler explains it
    return interior


def corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The 8 corners (8, 3) of the box [lo, hi]."""
    return np.array([[(lo, hi)[i >> k & 1][k] for k in range(3)] for i in range(8)], dtype=float)
