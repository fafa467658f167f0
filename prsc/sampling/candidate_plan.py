"""The candidate plan: how the candidate sampler (candidates.py) draws each object of a spec
and what it tests, decided once per spec; Unbatchable when some object's region or test
is not one it vectorises (the spec's joint law is then drawn by Gibbs sweeps only).

As the rejection reference (`--law rejection`, engine.py's joint mode) each object is drawn
uniformly on its whole region given the objects before it, with its own size and yaw
drawn first, and the scene is tested for collisions and rejection-checked requires. The
regions vectorised here:
- **fixed**: the same in every candidate (every rule static), drawn by its exact sampler;
- **carried**: one region translated with an earlier object (a camera above the bin), when
  the static rows provably never cut it (the batched sampler's proof, batched.py);
- **rectangle**: `[completely] on`/`in` an earlier object of fixed size (its top face or its
  container floor): a rectangle in that object's frame, shrunk by the footprint's support
  along its sides when `completely`, when the workspace provably holds it.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any, Callable, Sequence

import numpy as np

from prsc.constraints.model import ConstraintProgram, Rule
from prsc.constraints.specifiers import interior_of
from prsc.constraints.values import DIMENSIONS, ObjectValue
from prsc.errors import PrscError
from prsc.geometry.container import Interior
from prsc.geometry.exceptions import EmptyRegionError, UnboundedRegionError
from prsc.geometry.obb import CONTACT_TOL
from prsc.geometry.polytope import Polytope
from prsc.geometry.sampler import UniformSampler
from prsc.ir import model as ir
from prsc.sampling.batch_values import BatchValue, Unbatchable, _const
from prsc.sampling.batched import rows_hold
from prsc.constraints.specifiers import DIRECTION_AXES
from prsc.sampling.candidate_rules import Test, constant_region, support
from prsc.sampling.candidate_values import CandidateCompiler, CandidateState
from prsc.sampling.prepared import TOL
from prsc.sampling.runtime import ObjectRuntime

# Rows a.p <= b of each candidate on its own centre: (a (n, m, 3), b (n, m)).
Cut = Callable[[CandidateState], tuple[np.ndarray, np.ndarray]]
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
class Region:
    """Where a candidate's centre is drawn: its whole region given the objects before it."""

    kind: str  # fixed | carried | rectangle (cut by `cuts`: a convex polygon) | affine
    sampler: UniformSampler | None = None  # fixed, carried (about the anchor)
    point: np.ndarray | None = None  # fixed: a single point
    anchor: str | None = None  # carried, rectangle: the object it moves with
    interior: Interior | None = None  # rectangle: the container floor (None: the top face)
    half_size: tuple[float, float] = (0.0, 0.0)  # rectangle: the face's or floor's half width and length
    completely: bool = False  # rectangle: shrunk by the footprint
    cuts: tuple[Cut, ...] = ()  # rectangle: further rows a.p <= b per candidate (`left of tray`, ...)
    affine: AffineRows | None = None  # affine: carried rows and static rows on a point, line or plane

    @property
    def uniforms(self) -> int:
        """Uniforms one draw reads."""
        if self.affine is not None:
            return 3
        if self.sampler is not None:
            return self.sampler.dim + 1
        return 3 if self.cuts else 2


@dataclass(frozen=True, eq=False)
class CandidateObject:
    """One object of a candidate round: how its size, yaw and centre are drawn, what it must not hit."""

    name: str
    sizes: tuple[BatchValue, BatchValue, BatchValue]
    yaw: BatchValue | None
    rotation: np.ndarray  # when yaw is None
    region: Region
    obstacles: tuple[str, ...]  # earlier objects its box must not collide with

    @property
    def upright(self) -> bool:
        """Whether its box's third axis is vertical in every candidate (a yaw at most)."""
        r = self.rotation
        return self.yaw is not None or bool(r[2, 2] == 1.0 and r[0, 2] == r[1, 2] == r[2, 0] == r[2, 1] == 0.0)


@dataclass(frozen=True, eq=False)
class CandidatePlan:
    """A spec's objects as candidate rounds draw them, and the scene's tests."""

    objects: tuple[CandidateObject, ...]
    requires: tuple[tuple[int, Test], ...]  # (object index after which it is tested, -1: first), test
    soft: np.ndarray  # the soft requires' probabilities


@dataclass(frozen=True)
class _Placed:
    """What the plan knows of the objects before the one being planned."""

    runtimes: dict[str, ObjectRuntime]
    bounds: dict[str, tuple[np.ndarray, np.ndarray]]  # bounds of the centre in every candidate
    reaches: dict[str, float]  # bound of the box's half diagonal


def candidate_plan(cprog: ConstraintProgram, runtimes: Sequence[ObjectRuntime]) -> CandidatePlan:
    """The candidate plan of a lowered spec; Unbatchable says why its joint law needs Gibbs sweeps."""
    program = cprog.program
    decls = {o.name: o for o in program.objects}
    placed = _Placed({}, {}, {})
    compiler_bounds: dict[str, tuple[np.ndarray, np.ndarray, Any]] = {}
    compiler = CandidateCompiler(program, compiler_bounds)
    conditions = {label: req.condition for label, req in zip((c.label_id for _, c in cprog.require_tests), program.requires)}
    requires: list[tuple[int, Test]] = []
    for check in cprog.scene_checks:
        requires.append((-1, _require_test(compiler, conditions[check.label_id], check.soft)))
    objects: list[CandidateObject] = []
    for index, rt in enumerate(runtimes):
        plan = rt.plan
        name = plan.name
        if plan.exclusions:
            raise Unbatchable(f"{name} has excluded cells (`not visible from`, `reachable by`)")
        if rt.after_position:
            raise Unbatchable(f"{name}'s rotation depends on its position")
        if rt.allow_static is None:
            raise Unbatchable(f"{name}'s allowCollisions changes between scenes")
        if any(rule.soft is not None for rule in plan.rules if rule.kind != "require"):
            raise Unbatchable(f"{name}'s region has a soft rule")
        sizes = _sizes(rt, decls[name], compiler)
        yaw, rotation = _rotation(rt, compiler)
        reach = 0.5 * float(np.linalg.norm([s.hi[0] for s in sizes]))
        region, lo, hi = _region(rt, placed, reach, compiler)
        placed.bounds[name], placed.reaches[name], placed.runtimes[name] = (lo, hi), reach, rt
        compiler_bounds[name] = (lo, hi, None)
        obstacles = () if rt.allow_static else tuple(
            other.name for j, other in enumerate(objects)
            if not runtimes[j].allow_static and j not in plan.rests_in and not _apart(placed, name, other.name)
        )
        objects.append(CandidateObject(name, sizes, yaw, rotation, region, obstacles))
        requires += [(index, _require_test(compiler, conditions[c.label_id], c.soft)) for c in plan.checks]
        for rule in (r for r in plan.rules if r.kind == "require") if region.kind == "rectangle" else ():
            # A require lowered to rows that read no position of its own is a test on the scene, the same.
            condition = conditions.get(rule.label_id)
            if condition is None or _reads_position(condition, name):
                raise Unbatchable(f"{name}'s region has a require on its position")
            requires.append((index, _require_test(compiler, condition, rule.soft)))
    soft = np.array([s.probability for s in cprog.soft_requires], dtype=float)
    return CandidatePlan(tuple(objects), tuple(requires), soft)


def _sizes(rt: ObjectRuntime, decl: Any, compiler: CandidateCompiler) -> tuple[BatchValue, BatchValue, BatchValue]:
    """Width, length and height as candidate values (registered for `self.width` and later reads)."""
    name = rt.plan.name
    own: dict[str, BatchValue] = {}
    compiler.sizes[name] = own
    for i, prop in enumerate(DIMENSIONS):
        if rt.dims is not None:
            own[prop] = _const(rt.dims[i])
            continue
        expr = decl.prop(prop)
        if expr is None:
            raise Unbatchable(f"{name}'s {prop} is not a property")
        value = compiler.compile(expr)
        if value.vector or not value.lo[0] >= 0.0:
            raise Unbatchable(f"{name}'s {prop} may be negative")  # the scalar sampler explains it
        own[prop] = value
    return own["width"], own["length"], own["height"]


def _rotation(rt: ObjectRuntime, compiler: CandidateCompiler) -> tuple[BatchValue | None, np.ndarray]:
    if rt.rotation is not None:
        return None, rt.rotation
    rule = rt.plan.orientation
    assert rule is not None
    if rule.kind != "facing":
        raise Unbatchable(f"{rt.plan.name}'s `{rule.kind}` changes between scenes")
    value = compiler.compile(rule.arg)
    if value.vector:
        raise Unbatchable(f"{rt.plan.name} faces a direction that changes between scenes")
    return value, np.eye(3)


def _region(rt: ObjectRuntime, placed: _Placed, reach: float, compiler: CandidateCompiler
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
    return _rectangle(rt, placed, reach, compiler)


def _carried(rt: ObjectRuntime, placed: _Placed) -> tuple[Region, np.ndarray, np.ndarray]:
    """A region translated with an earlier object, which the static rows never cut (batched._anchored)."""
    provider, name = rt.provider, rt.plan.name
    anchor = provider.plan.anchor
    provider.fixed_bounds()
    prepared = provider.anchored_prepared
    if prepared is None or prepared.sampler is None or anchor not in placed.bounds:
        raise Unbatchable(f"{name}'s region carried by {anchor} may be cut, or is a point")
    own = np.unique(prepared.sampler.vertices(), axis=0)
    lo_a, hi_a = placed.bounds[anchor]
    anchors = _corners(lo_a, hi_a)
    carried = (anchors[:, None, :] + own[None, :, :]).reshape(-1, 3)
    static = provider.static_rows
    if static is not None and (len(static.d) or not rows_hold(static, carried, 2 * TOL)):
        raise Unbatchable(f"{name}'s region carried by {anchor} may be cut by its static rows")
    return Region("carried", prepared.sampler, anchor=anchor), carried.min(axis=0), carried.max(axis=0)


def _affine(rt: ObjectRuntime, placed: _Placed) -> tuple[Region, np.ndarray, np.ndarray]:
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


def _rectangle(rt: ObjectRuntime, placed: _Placed, reach: float, compiler: CandidateCompiler
               ) -> tuple[Region, np.ndarray, np.ndarray]:
    """`[completely] on`/`in` an earlier object of fixed size, inside the workspace, cut by the
    object's other rules (directions, fixed or carried rows) into a convex polygon."""
    name = rt.plan.name
    surfaces = [r for r in rt.plan.rules if r.kind == "on"]
    if len(surfaces) != 1:
        kinds = sorted({r.kind for r in rt.plan.rules})
        raise Unbatchable(f"{name}'s region ({', '.join(kinds)}) is not on one object")
    cuts = tuple(_cut(r, rt, placed, compiler) for r in rt.plan.rules if r.kind not in ("on", "workspace", "require"))
    rule = surfaces[0]
    target = rule.args[0]
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
    completely = bool(rule.option("completely"))
    lift = interior.floor_top if interior is not None else carrier.dims[2] / 2
    # The object's box lies in this prism on the face, in the carrier's frame (beyond its sides
    # by up to its reach unless `completely`); the centre in the same prism.
    over = 0.0 if completely else reach
    prism = _corners(np.array([-half[0] - over, -half[1] - over, lift]), np.array([half[0] + over, half[1] + over, lift + 2 * reach]))
    lo_c, hi_c = placed.bounds[target.name]
    if carrier.rotation is not None:
        offsets = prism @ carrier.rotation.T
        lo, hi = lo_c + offsets.min(axis=0), hi_c + offsets.max(axis=0)
    else:
        radius = float(np.linalg.norm(prism, axis=1).max())
        lo, hi = lo_c - radius, hi_c + radius
    for workspace in (r for r in rt.plan.rules if r.kind == "workspace"):
        if not rows_hold(constant_region(workspace), _corners(lo, hi)):
            raise Unbatchable(f"{name}'s region may be cut by the workspace")
    return Region("rectangle", anchor=target.name, interior=interior, half_size=half,
                  completely=completely, cuts=cuts), lo, hi


def _cut(rule: Rule, rt: ObjectRuntime, placed: _Placed, compiler: CandidateCompiler) -> Cut:
    """A rule that cuts the rectangle, as rows per candidate: a direction (specifiers.rows_direction),
    or rows the compiler fixed for every scene (a static template, or one carried by an anchor for
    an object of fixed size and rotation)."""
    me = rt.plan.name
    template = rule.template
    if template is not None and (template.anchor is None or rt.support is not None):
        rows, anchor = template.rows, template.anchor
        if len(rows.d) or (anchor is not None and anchor not in placed.runtimes):
            raise Unbatchable(f"{me}'s `{rule.kind}` rows are equalities or carried by a later object")
        a, b = rows.A, rows.b

        def fixed(state: CandidateState) -> tuple[np.ndarray, np.ndarray]:
            n = len(state.keys)
            shift = 0.0 if anchor is None else state.positions[anchor] @ a.T
            return np.broadcast_to(a, (n,) + a.shape), np.broadcast_to(b + shift, (n, len(b)))

        return fixed
    if rule.kind != "direction":
        raise Unbatchable(f"{me}'s `{rule.kind}` rule")
    target = rule.args[0]
    if not isinstance(target, ir.ObjectRef) or target.name not in placed.runtimes:
        raise Unbatchable(f"{me} is placed relative to something other than an object placed before it")
    by = compiler.compile(rule.args[1]) if len(rule.args) > 1 else None
    up_to = compiler.compile(rule.args[2]) if len(rule.args) > 2 else None
    if any(v is not None and v.vector for v in (by, up_to)):
        raise Unbatchable(f"{me}'s distance from {target.name} is a vector")
    if by is not None and up_to is not None and not up_to.lo[0] > by.hi[0]:
        raise Unbatchable(f"{me}'s band beside {target.name} may be a line")  # a segment, not a polygon
    axis, other = DIRECTION_AXES[rule.option("relation")], target.name

    def direction(state: CandidateState) -> tuple[np.ndarray, np.ndarray]:
        # n.(p - X) >= d + s(n), and <= e + s(n) with `by (d, e)`.
        n = state.rotations[other] @ axis
        base = np.einsum("ni,ni->n", n, state.positions[other]) \
            + support(n[:, None, :], state.rotations[me], state.dims[me] * 0.5)[:, 0]
        low = base if by is None else base + by.fn(state)[:, 0]
        if up_to is None:
            return -n[:, None, :], -low[:, None]
        return np.stack([-n, n], axis=1), np.stack([-low, base + up_to.fn(state)[:, 0]], axis=1)

    return direction


def _reads_position(expr: Any, name: str) -> bool:
    """Whether an expression reads the object's position (anything of it but its size), conservatively."""
    if isinstance(expr, ir.PropertyRef) and isinstance(expr.target, ir.ObjectRef) and expr.target.name == name:
        return expr.prop not in DIMENSIONS
    if isinstance(expr, ir.ObjectRef):
        return expr.name == name
    if isinstance(expr, tuple):
        return any(_reads_position(e, name) for e in expr)
    if isinstance(expr, ir.Expr):
        return any(_reads_position(getattr(expr, f.name), name) for f in fields(expr))
    return False


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


def _require_test(compiler: CandidateCompiler, condition: ir.Expr, soft: int | None) -> Test:
    value = compiler.compile(condition)
    if value.vector:
        raise Unbatchable("a require on a vector")
    fn = value.fn
    if soft is None:
        return lambda state: np.broadcast_to(fn(state)[:, 0] != 0.0, (len(state.keys),))
    return lambda state: (fn(state)[:, 0] != 0.0) | ~state.active[:, soft]  # type: ignore[index]


def _corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    return np.array([[(lo, hi)[i >> k & 1][k] for k in range(3)] for i in range(8)], dtype=float)


def _apart(placed: _Placed, a: str, b: str) -> bool:
    """Whether two objects' boxes are apart in every candidate (their centres' bounds and sizes)."""
    (lo_a, hi_a), (lo_b, hi_b) = placed.bounds[a], placed.bounds[b]
    gap = placed.reaches[a] + placed.reaches[b] - CONTACT_TOL
    return bool(np.any(hi_a + gap <= lo_b) or np.any(hi_b + gap <= lo_a))
