"""Lower the typed IR (prsc.ir.model.Program) to the polytope constraint IR (model.py).

Per object, in dependency order: compile its properties, its orientation and one
position rule per specifier, plus the workspace containment and every `require` that is
linear in its position and mentions no later object. A rule whose rows are the same in
every scene (found by evaluating it against a StaticContext, which refuses random draws)
is built once here; an empty intersection of such rows is reported now, naming an
irreducible infeasible subset of the specifiers with their source lines.
"""

from __future__ import annotations

import functools
from typing import Any, Callable

import numpy as np

from prsc.constraints import specifiers as rows
from prsc.constraints.context import NotStatic, SceneContext, StaticContext
from prsc.constraints.evaluate import Compiled, ExprCompiler, StaticFacts, truthy
from prsc.constraints.model import (
    CONTAINMENT,
    POSITION,
    RELATIVE,
    REQUIRE,
    ConstraintProgram,
    ObjectPlan,
    OrientationRule,
    PositionRule,
    RegionRules,
    RequireCheck,
    RowLabel,
    SoftRequire,
    Support,
)
from prsc.constraints.regions import rotation_of
from prsc.constraints.requires import lower_condition, mentioned_objects
from prsc.constraints.values import DIMENSIONS, ObjectValue, OrientedPoint, RegionValue, as_position, dimension, static_dims
from prsc.errors import PrscError, Span
from prsc.geometry.exceptions import GeometryError
from prsc.geometry.iis import irreducible_infeasible_subset, is_feasible
from prsc.geometry.lp import solve_lp
from prsc.geometry.polytope import Polytope, intersect
from prsc.geometry.rotations import rotation_taking_y_to, yaw_matrix, yaw_toward
from prsc.ir import model as ir



@functools.lru_cache(maxsize=64)
def _file_lines(path: str) -> tuple[str, ...]:
    try:
        with open(path, encoding="utf-8", errors="replace") as handle:
            return tuple(handle.read().splitlines())
    except OSError:
        return ()


def source_text(span: Span | None, fallback: str = "") -> str:
    """The source text a span covers, on one line (whitespace collapsed)."""
    if span is None:
        return fallback
    lines = _file_lines(span.path)
    if not lines or span.line > len(lines):
        return fallback
    if span.end_line == span.line:
        text = lines[span.line - 1][span.column - 1 : span.end_column - 1]
    else:
        parts = [lines[span.line - 1][span.column - 1 :]]
        parts += lines[span.line : span.end_line - 1]
        if span.end_line <= len(lines):
            parts.append(lines[span.end_line - 1][: span.end_column - 1])
        text = " ".join(parts)
    text = " ".join(text.split())
    return text or fallback


def _spec_text(spec: ir.Specifier) -> str:
    """Source text of a specifier, or a readable stand-in."""
    return source_text(spec.span, type(spec).__name__.lower())


class _ProgramLowering:
    """State while lowering one program."""

    def __init__(self, program: ir.Program) -> None:
        self.program = program
        self.facts = StaticFacts()
        self.compiler = ExprCompiler(program, self.facts)
        self.labels: list[RowLabel] = []
        self.index_of = {obj.name: i for i, obj in enumerate(program.objects)}
        self.declarations = {obj.name: obj.span for obj in program.objects}
        self.workspace: Compiled | None = None
        # The workspace's bounding box (the rejection baseline draws from it), when static.
        self.workspace_box: Polytope | None = None
        if program.workspace is not None:
            self.workspace = self.compiler.compile(program.workspace)
            if self.workspace.const and isinstance(self.workspace.value, RegionValue):
                self.workspace_box = _bounding_box(self.workspace.value.poly)

    def label(self, obj: str, text: str, span: Span | None, cause: str, refs: tuple[str, ...] = ()) -> int:
        """Register a row label; returns its id."""
        self.labels.append(RowLabel(obj, text, span, cause, tuple(r for r in refs if r != obj)))
        return len(self.labels) - 1

    def static_context(self, extra: ObjectValue | None = None) -> StaticContext:
        """A probe context holding every object known at compile time (and `extra`)."""
        objects = dict(self.facts.objects)
        if extra is not None:
            objects[extra.name] = extra
        return StaticContext(objects)


def _bounding_box(poly: Polytope) -> Polytope | None:
    """The axis-aligned bounding box of a region (6 LPs), or None if it is unbounded or empty."""
    lo, hi = np.zeros(3), np.zeros(3)
    for axis in range(3):
        for sign in (1.0, -1.0):
            cost = np.zeros(3)
            cost[axis] = sign
            sol = solve_lp(cost, np.vstack([poly.A, poly.C]), np.concatenate([np.full(len(poly.b), -np.inf), poly.d]), np.concatenate([poly.b, poly.d]))
            if sol.status != "optimal":
                return None
            if sign > 0:
                lo[axis] = sol.x[axis]
            else:
                hi[axis] = sol.x[axis]
    eye = np.eye(3)
    return Polytope.from_rows(np.vstack([eye, -eye]), np.concatenate([hi, -lo]))


def _probe(fn: Callable[[SceneContext], Any], ctx: StaticContext) -> tuple[bool, Any]:
    """(True, value) if fn gives the same value in every scene, else (False, None)."""
    try:
        return True, fn(ctx)
    except (NotStatic, PrscError):
        return False, None


class _DynamicSupport(Support):
    """Stands for a support function that is not known at compile time."""

    def __init__(self) -> None:
        super().__init__(None, np.zeros(3), "free")

    def __call__(self, normals: np.ndarray) -> np.ndarray:
        raise NotStatic


# ---------------------------------------------------------------- orientation


def _orientation_rule(low: _ProgramLowering, obj: ir.ObjectDecl) -> OrientationRule | None:
    """The object's orientation rule (the last specifier setting orientation wins)."""
    spec = None
    for s in obj.specifiers:
        if "orientation" in s.sets:
            spec = s
    if spec is None:
        return None
    label = low.label(obj.name, _spec_text(spec), spec.span, POSITION)
    span = spec.span
    if isinstance(spec, ir.FacingToward):
        target = low.compiler.compile(spec.target).fn

        def toward(ctx: SceneContext, me: ObjectValue) -> np.ndarray:
            goal = as_position(target(ctx))
            if goal is None:
                raise PrscError("'facing toward' needs an object or a point", span)
            assert me.position is not None
            direction = goal - me.position
            if float(np.hypot(direction[0], direction[1])) == 0.0:
                return np.eye(3)  # straight above or below: every yaw faces it
            return yaw_matrix(yaw_toward(direction))

        return OrientationRule(label, True, "yaw", toward)
    if isinstance(spec, ir.Facing):
        value = low.compiler.compile(spec.direction).fn

        def facing(ctx: SceneContext, me: ObjectValue) -> np.ndarray:
            v = value(ctx)
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                return yaw_matrix(float(v))
            if isinstance(v, OrientedPoint):
                return v.rotation
            pos = as_position(v)
            if pos is None:
                raise PrscError("'facing' needs a vector or an angle", span)
            try:
                return rotation_taking_y_to(pos)
            except ValueError as error:
                raise PrscError(f"'facing': {error}", span) from error

        compute = facing
    elif isinstance(spec, ir.With):
        value = low.compiler.compile(spec.value).fn

        def with_orientation(ctx: SceneContext, me: ObjectValue) -> np.ndarray:
            v = value(ctx)
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                return yaw_matrix(float(v))
            return rotation_of(v, span)

        compute = with_orientation
    else:
        raise PrscError(f"unsupported orientation specifier {type(spec).__name__}", span)
    after = "position" in spec.reads
    return OrientationRule(label, after, "free" if after else "exact", compute)


# ---------------------------------------------------------------- position rules


def _cause(spec: ir.Specifier) -> str:
    if isinstance(spec, (ir.Direction, ir.AlignedWith)):
        return RELATIVE
    if isinstance(spec, (ir.In, ir.On)):
        return CONTAINMENT
    return POSITION


Make = Callable[[list[Any], Support], Polytope]


def _specifier_rule(
    low: _ProgramLowering, obj: ir.ObjectDecl, spec: ir.Specifier
) -> tuple[int, list[Compiled], Make, Make | None] | None:
    """(label, compiled arguments, rows builder, baseline draw-region builder) of a position specifier.

    The baseline builder gives the rows the rejection baseline draws from (equalities,
    the `on` surface without erosion), None when the specifier is only a test there.
    None for specifiers that do not set the position.
    """
    if "position" not in spec.sets:
        return None
    compile_ = low.compiler.compile
    span = spec.span
    refs: set[str] = set()
    for value in vars(spec).values():
        if isinstance(value, ir.Expr):
            refs |= mentioned_objects(value)
    label = low.label(obj.name, _spec_text(spec), span, _cause(spec), tuple(sorted(refs)))
    if isinstance(spec, ir.At) or (isinstance(spec, ir.With) and spec.prop == "position"):
        point = spec.point if isinstance(spec, ir.At) else spec.value

        def at(a: list[Any], s: Support) -> Polytope:
            return rows.rows_at(a[0], label, span)

        return label, [compile_(point)], at, at
    if isinstance(spec, ir.Beyond):
        def beyond(a: list[Any], s: Support) -> Polytope:
            return rows.rows_beyond(a[0], a[1], a[2], label, span)

        return label, [compile_(spec.target), compile_(spec.by), compile_(spec.origin)], beyond, beyond
    if isinstance(spec, ir.In):
        completely = spec.completely
        return label, [compile_(spec.region)], lambda a, s: rows.rows_in(a[0], completely, s, label, span), None
    if isinstance(spec, ir.On):
        completely = spec.completely
        return (
            label,
            [compile_(spec.target)],
            lambda a, s: rows.rows_on(a[0], completely, s, label, span),
            lambda a, s: rows.rows_on(a[0], False, s, label, span),
        )
    if isinstance(spec, ir.Direction):
        relation = spec.relation
        if relation not in rows.DIRECTION_AXES:
            raise PrscError(f"unknown direction {relation!r}", span)
        args = [compile_(spec.target)] + ([compile_(spec.by)] if spec.by is not None else [])
        return label, args, lambda a, s: rows.rows_direction(relation, a[0], a[1] if len(a) > 1 else None, s, label, span), None
    if isinstance(spec, ir.AlignedWith):
        axis = spec.axis.strip("'\"").lower()
        if axis not in ("x", "y", "z"):
            raise PrscError(f"'aligned with' needs the axis x, y or z, not {spec.axis!r}", span)

        def aligned(a: list[Any], s: Support) -> Polytope:
            return rows.rows_aligned(a[0], axis, label, span)

        return label, [compile_(spec.target)], aligned, aligned
    raise PrscError(f"unsupported position specifier {type(spec).__name__}", span)


def _position_rule(
    label: int,
    build: Callable[[SceneContext, Support], Polytope],
    probe_ctx: StaticContext,
    probe_support: Support,
    soft: int | None,
) -> PositionRule:
    """A PositionRule from `build`; a hard one whose rows are the same in every scene is built once now."""
    if soft is None:
        static, poly = _probe(lambda ctx: build(ctx, probe_support), probe_ctx)
        if static:
            return PositionRule(label, True, build, poly)
    return PositionRule(label, False, build, None, soft)


def _make_rule(
    label: int,
    args: list[Compiled],
    make: Callable[[list[Any], Support], Polytope],
    probe_ctx: StaticContext,
    probe_support: Support,
    soft: int | None = None,
) -> PositionRule:
    """A PositionRule whose rows `make` builds from the values of `args` (and the support)."""
    fns = [a.fn for a in args]

    def build(ctx: SceneContext, support: Support) -> Polytope:
        return make([f(ctx) for f in fns], support)

    return _position_rule(label, build, probe_ctx, probe_support, soft)


def _require_rule(
    low: _ProgramLowering, target: str, req: ir.Require, label: int, soft: int | None,
    probe_ctx: StaticContext, probe_support: Support,
) -> PositionRule | None:
    """A lowered require as a PositionRule, or None when it is not linear in target's position."""
    cond = lower_condition(low.compiler, req.condition, target)
    if cond is None:
        return None

    def build(ctx: SceneContext, support: Support) -> Polytope:
        le_a, le_b, eq_a, eq_b = cond(ctx)
        a = np.array(le_a, dtype=float).reshape(-1, 3)
        c = np.array(eq_a, dtype=float).reshape(-1, 3)
        return Polytope(a, np.array(le_b, dtype=float), c, np.array(eq_b, dtype=float), np.full(len(a), label), np.full(len(c), label))

    return _position_rule(label, build, probe_ctx, probe_support, soft)


# ---------------------------------------------------------------- errors


def infeasible_error(
    labels: list[RowLabel] | tuple[RowLabel, ...], ids: tuple[int, ...], obj: str, span: Span | None, what: str,
    declarations: dict[str, Span] | None = None,
) -> PrscError:
    """The error for an empty region: names each conflicting specifier with its source line."""
    conflicting = [labels[i] for i in ids]
    if not conflicting:
        message = f"{what}: {obj} has no position inside the workspace"
    elif len(conflicting) == 1:
        message = f"{what}: no position of {obj} satisfies '{conflicting[0].text}'"
    else:
        names = ", ".join(f"'{lab.text}'" for lab in conflicting)
        message = f"{what}: no position of {obj} satisfies {names} together"
    notes: list[tuple[str, Span | None]] = []
    for lab in conflicting:
        owner = "" if lab.object == obj or not lab.object else f" (of {lab.object})"
        notes.append((f"conflicting: {lab.text}{owner}", lab.span))
    seen: set[str] = set()
    for lab in conflicting:
        for ref in lab.refs:
            if declarations and ref in declarations and ref not in seen:
                seen.add(ref)
                notes.append((f"{ref} is declared here", declarations[ref]))
    return PrscError(message, span, tuple(notes))


def explain_empty(
    labels: list[RowLabel] | tuple[RowLabel, ...], poly: Polytope, obj: str, span: Span | None, what: str,
    declarations: dict[str, Span] | None = None,
) -> PrscError:
    """An infeasibility error for rows `poly`, with an irreducible infeasible subset."""
    try:
        ids = irreducible_infeasible_subset(poly)
    except ValueError:
        ids = tuple(sorted({int(i) for i in np.concatenate([poly.labels, poly.eq_labels]) if i >= 0}))
    return infeasible_error(labels, ids, obj, span, what, declarations)


def numeric_failure(obj: str, span: Span | None, error: GeometryError) -> PrscError:
    """A solver failure on an object's rows as an error at the object.

    Seen with coordinates or sizes far beyond any scene (1e300 m): the LPs cannot be
    solved in floating point, which is the spec's doing, not a bug in prsc."""
    return PrscError(
        f"cannot place {obj}: its constraints could not be solved numerically ({error}); "
        "are its numbers (metres, radians) within a sensible range?", span,
    )


# ---------------------------------------------------------------- objects


def _lower_object(
    low: _ProgramLowering,
    obj: ir.ObjectDecl,
    requires: list[tuple[int, ir.Require]],
    soft_index: dict[int, int],
    require_labels: dict[int, int],
) -> ObjectPlan:
    name = obj.name
    facts = low.facts
    facts.props[name] = {}
    property_fns: dict[str, Callable[[SceneContext], Any]] = {}
    for prop, expr in obj.properties:
        compiled = low.compiler.compile(expr)
        property_fns[prop] = compiled.fn
        if compiled.const:
            facts.props[name][prop] = compiled.value
    for dim in DIMENSIONS:
        if dim not in property_fns:
            property_fns[dim] = lambda ctx: 1.0
            facts.props[name][dim] = 1.0
    static_props = dict(facts.props[name])
    for dim in DIMENSIONS:
        if dim in static_props:
            expr = obj.prop(dim)
            dimension(static_props[dim], dim, name, expr.span if expr is not None else obj.span)
    dims = static_dims(static_props)

    orientation = _orientation_rule(low, obj)
    rotation: np.ndarray | None = np.eye(3) if orientation is None else None
    me = ObjectValue(name, obj.class_name, obj.span, None, None, dims, dict(static_props))
    if orientation is not None and not orientation.after_position:
        me.rotation = None
        ok, value = _probe(lambda ctx: orientation.compute(ctx, ctx.objects[name]), low.static_context(me))
        if ok:
            rotation = np.asarray(value, dtype=float)
            orientation = OrientationRule(orientation.label_id, False, "exact", orientation.compute, rotation)
    me.rotation = rotation
    if dims is not None and (rotation is not None or (orientation is not None and orientation.after_position)):
        mode = "exact" if rotation is not None else orientation.bound_mode  # type: ignore[union-attr]
        probe_support: Support = Support(rotation, np.array(dims) * 0.5, mode)
    else:
        probe_support = _DynamicSupport()
    probe_ctx = low.static_context(me)

    rules: list[PositionRule] = []
    base_rules: list[PositionRule] = []
    for spec in obj.specifiers:
        lowered = _specifier_rule(low, obj, spec)
        if lowered is None:
            continue
        label, args, make, base_make = lowered
        rules.append(_make_rule(label, args, make, probe_ctx, probe_support))
        if base_make is not None:
            base_rules.append(_make_rule(label, args, base_make, probe_ctx, probe_support))
    if low.workspace is not None:
        ws_span = low.program.workspace.span if low.program.workspace is not None else None
        ws_label = low.label(name, "workspace", ws_span, CONTAINMENT)
        rules.append(
            _make_rule(ws_label, [low.workspace], lambda a, s: rows.rows_in(a[0], True, s, ws_label, ws_span), probe_ctx, probe_support)
        )
        if low.workspace_box is not None:
            box = low.workspace_box.with_label(ws_label)
            base_rules.append(PositionRule(ws_label, True, lambda ctx, s: box, box))
    checks: list[RequireCheck] = []
    can_lower = orientation is None or not orientation.after_position
    anchor_candidates = set(obj.depends_on)
    for k, req in requires:
        label = require_labels[k]
        soft = soft_index.get(k)
        rule = _require_rule(low, name, req, label, soft, probe_ctx, probe_support) if can_lower else None
        if rule is not None:
            rules.append(rule)
            anchor_candidates |= mentioned_objects(req.condition)
        else:
            test = low.compiler.compile(req.condition).fn
            checks.append(RequireCheck(label, functools.partial(_holds, test, req.span), soft))

    region = _region_rules(low, me, rules, anchor_candidates, probe_support)
    if region.static_rows is not None and not is_feasible(region.static_rows):
        raise explain_empty(low.labels, region.static_rows, name, obj.span, "infeasible specification", low.declarations)
    base_region = _region_rules(low, me, base_rules, set(obj.depends_on), probe_support)
    static_position = None if region.static_rows is None else _pinned_point(region.static_rows)
    if static_position is not None:
        facts.positions[name] = static_position
        if rotation is not None and dims is not None:
            facts.objects[name] = ObjectValue(name, obj.class_name, obj.span, static_position, rotation, dims, dict(static_props))
    if rotation is not None:
        facts.rotations[name] = rotation
    return ObjectPlan(
        index=low.index_of[name],
        name=name,
        class_name=obj.class_name,
        anonymous=obj.anonymous,
        span=obj.span,
        property_fns=property_fns,
        static_props=static_props,
        orientation=orientation,
        region=region,
        checks=tuple(checks),
        depends_on=tuple(obj.depends_on),
        base_region=base_region,
        static_position=static_position,
    )


def _region_rules(
    low: _ProgramLowering, me: ObjectValue, rules: list[PositionRule], candidates: set[str], support: Support
) -> RegionRules:
    """Stack the static rules; find an anchor for the dynamic ones if there is one."""
    static_list = [r.rows for r in rules if r.static and r.rows is not None]
    static_rows = intersect(*static_list) if static_list else None
    dynamic = [r for r in rules if not r.static]
    anchor, anchored_rows = None, None
    if dynamic and all(r.soft is None for r in dynamic) and not isinstance(support, _DynamicSupport):
        anchor, anchored_rows = _find_anchor(low, me, dynamic, candidates, support)
    return RegionRules(tuple(rules), static_rows, anchor, anchored_rows)


_TEST_SHIFTS = (np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0]))


def _find_anchor(
    low: _ProgramLowering, me: ObjectValue, dynamic: list[PositionRule], candidates: set[str], support: Support
) -> tuple[str | None, Polytope | None]:
    """An earlier object whose position alone moves the dynamic rows rigidly, and those rows at its origin.

    The rows are affine in the anchor's position (its rotation and size being fixed), so
    comparing the rows at the origin and at the three unit shifts proves they translate
    with it (a require like `c.x < 2 * t.x` does not, and is not anchored).
    """
    order = sorted((low.index_of[n] for n in candidates if n in low.index_of and n != me.name), reverse=True)
    for index in order:
        x = low.program.objects[index]
        xname = x.name
        if xname in low.facts.positions or xname not in low.facts.rotations:
            continue
        props = low.facts.props.get(xname, {})
        dims = static_dims(props)
        if dims is None:
            continue

        def rows_at_shift(shift: np.ndarray) -> Polytope | None:
            stand_in = ObjectValue(xname, x.class_name, x.span, shift, low.facts.rotations[xname], dims, dict(props))
            ctx = low.static_context(me)
            ctx.objects[xname] = stand_in
            built = []
            for rule in dynamic:
                ok, poly = _probe(lambda c: rule.build(c, support), ctx)
                if not ok:
                    return None
                built.append(poly)
            return intersect(*built)

        base = rows_at_shift(np.zeros(3))
        if base is None:
            continue
        rigid = True
        for shift in _TEST_SHIFTS:
            moved = rows_at_shift(shift)
            if moved is None or not _translates(base, moved, shift):
                rigid = False
                break
        if rigid:
            return xname, base
    return None, None


def _translates(base: Polytope, moved: Polytope, shift: np.ndarray, tol: float = 1e-12) -> bool:
    """Whether `moved` is `base` translated by `shift` (same rows, offsets moved by A.shift)."""
    if base.A.shape != moved.A.shape or base.C.shape != moved.C.shape:
        return False
    scale = 1.0 + float(np.max(np.abs(np.concatenate([base.b, base.d, [0.0]]))))
    return (
        np.allclose(base.A, moved.A, rtol=0, atol=tol)
        and np.allclose(base.C, moved.C, rtol=0, atol=tol)
        and np.allclose(base.b + base.A @ shift, moved.b, rtol=0, atol=tol * scale)
        and np.allclose(base.d + base.C @ shift, moved.d, rtol=0, atol=tol * scale)
    )


def _holds(test: Callable[[SceneContext], Any], span: Span, ctx: SceneContext) -> bool:
    return truthy(test(ctx), span)


def _pinned_point(poly: Polytope) -> np.ndarray | None:
    """The single point the equality rows fix (rank 3), else None."""
    if poly.C.shape[0] < 3:
        return None
    u, s, vt = np.linalg.svd(poly.C)
    if s[2] <= 1e-9 * max(1.0, s[0]):
        return None
    point, *_ = np.linalg.lstsq(poly.C, poly.d, rcond=None)
    return point


# ---------------------------------------------------------------- program


def lower_program(program: ir.Program) -> ConstraintProgram:
    """Lower a typed Program to the constraint IR; PrscError for a provably empty region."""
    low = _ProgramLowering(program)
    per_object: dict[str, list[tuple[int, ir.Require]]] = {o.name: [] for o in program.objects}
    scene_level: list[int] = []
    soft: list[SoftRequire] = []
    soft_index: dict[int, int] = {}
    require_labels: dict[int, int] = {}
    last_of: dict[int, int] = {}
    for k, req in enumerate(program.requires):
        names = mentioned_objects(req.condition)
        unknown = sorted(n for n in names if n not in low.index_of)
        if unknown:
            raise PrscError(f"require mentions unknown object {unknown[0]}", req.span)
        label = low.label("", "require " + source_text(req.condition.span, "condition"), req.span, REQUIRE)
        require_labels[k] = label
        if not 0.0 <= req.probability <= 1.0:
            raise PrscError(f"require[p] needs 0 <= p <= 1, got {req.probability}", req.span)
        if req.probability < 1.0:
            soft_index[k] = len(soft)
            soft.append(SoftRequire(len(soft), req.probability, label))
        if names:
            last = max(low.index_of[n] for n in names)
            last_of[k] = last
            per_object[program.objects[last].name].append((k, req))
        else:
            last_of[k] = -1
            scene_level.append(k)
    # Relabel: a require's rows belong to the object they were lowered onto.
    for k, last in last_of.items():
        if last >= 0:
            lab = low.labels[require_labels[k]]
            low.labels[require_labels[k]] = RowLabel(
                program.objects[last].name, lab.text, lab.span, lab.cause,
                tuple(sorted(n for n in mentioned_objects(program.requires[k].condition) if n != program.objects[last].name)),
            )

    plans = []
    for obj in program.objects:
        try:
            plans.append(_lower_object(low, obj, per_object[obj.name], soft_index, require_labels))
        except GeometryError as error:
            raise numeric_failure(obj.name, obj.span, error) from error

    scene_checks = []
    require_tests = []
    for k, req in enumerate(program.requires):
        test = functools.partial(_holds, low.compiler.compile(req.condition).fn, req.span)
        check = RequireCheck(require_labels[k], test, soft_index.get(k))
        require_tests.append((last_of[k], check))
        if last_of[k] < 0:
            scene_checks.append(check)
    params = tuple((p.name, low.compiler.compile(p.value).fn) for p in program.params)
    lowered = {}
    for plan in plans:
        ids = tuple(r.label_id for r in plan.rules if low.labels[r.label_id].cause == REQUIRE)
        if ids:
            lowered[plan.name] = ids
    return ConstraintProgram(
        program=program,
        objects=tuple(plans),
        labels=tuple(low.labels),
        scene_checks=tuple(scene_checks),
        soft_requires=tuple(soft),
        params=params,
        require_tests=tuple(require_tests),
        lowered_requires=lowered,
    )
