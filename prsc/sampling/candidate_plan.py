"""The candidate plan: how candidate rounds (candidates.py) draw each object of a spec and what
they test, decided once per spec; Unbatchable when some object's region (candidate_regions.py)
or test is not one they vectorise (the spec's joint law is then drawn by Gibbs sweeps only).

As the rejection reference (`--law rejection`, engine.py's joint mode) each object's size
and yaw are drawn from their priors, its centre uniformly on its whole region given the
objects before it, and the scene is tested for collisions and rejection-checked requires.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any, Sequence

import numpy as np

from prsc.constraints.polytope_ir import ConstraintProgram
from prsc.constraints.reach_rows import local_ring
from prsc.constraints.values import DIMENSIONS
from prsc.ir import model as ir
from prsc.sampling.batch_values import BatchValue, Unbatchable, _const
from prsc.sampling.candidate_cuts import Placed, inside_test, rows_test, tested_not_cut
from prsc.sampling.candidate_regions import Region, object_region
from prsc.sampling.candidate_rules import Test
from prsc.sampling.candidate_values import CandidateCompiler
from prsc.sampling.collisions import apart
from prsc.sampling.runtime import ObjectRuntime


@dataclass(frozen=True, eq=False)
class CandidateObject:
    """One object of a candidate round: how its size, yaw and centre are drawn, what it must not hit."""

    name: str
    sizes: tuple[BatchValue, BatchValue, BatchValue]
    yaw: BatchValue | None
    rotation: np.ndarray  # when yaw is None
    region: Region
    obstacles: tuple[str, ...]  # earlier objects its box must not collide with
    toward: BatchValue | None = None  # `facing toward` this point: a yaw from its centre, once drawn
    bounds: tuple[np.ndarray, np.ndarray] | None = None  # bounds of its centre in every candidate
    reach: float = 0.0  # bound of its box's half diagonal in every candidate

    @property
    def upright(self) -> bool:
        """Whether its box's third axis is vertical in every candidate (a yaw at most)."""
        r = self.rotation
        return self.yaw is not None or self.toward is not None or bool(r[2, 2] == 1.0 and r[0, 2] == r[1, 2] == r[2, 0] == r[2, 1] == 0.0)


@dataclass(frozen=True, eq=False)
class CandidatePlan:
    """A spec's objects as candidate rounds draw them, and the scene's tests."""

    objects: tuple[CandidateObject, ...]
    requires: tuple[tuple[int, Test], ...]  # (object index after which it is tested, -1: first), test
    soft: np.ndarray  # the soft requires' probabilities


def candidate_plan(cprog: ConstraintProgram, runtimes: Sequence[ObjectRuntime]) -> CandidatePlan:
    """The candidate plan of a lowered spec; Unbatchable says why its joint law needs Gibbs sweeps."""
    program = cprog.program
    decls = {o.name: o for o in program.objects}
    placed = Placed({}, {}, {})
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
        if rt.after_position and rt.provider.mode != "static" and rt.provider.point_rule is None:
            raise Unbatchable(f"{name}'s rotation depends on its position, and its region on its rotation")
        if rt.allow_static is None:
            raise Unbatchable(f"{name}'s allowCollisions changes between scenes")
        if any(rule.soft is not None for rule in plan.rules if rule.kind != "require"):
            raise Unbatchable(f"{name}'s region has a soft rule")
        sizes = _sizes(rt, decls[name], compiler)
        yaw, rotation, toward = _rotation(rt, compiler)
        reach = 0.5 * float(np.linalg.norm([s.hi[0] for s in sizes]))
        region, lo, hi = object_region(rt, placed, reach, compiler)
        placed.bounds[name], placed.reaches[name], placed.runtimes[name] = (lo, hi), reach, rt
        compiler_bounds[name] = (lo, hi, None)
        obstacles = () if rt.allow_static else tuple(
            other.name for j, other in enumerate(objects)
            if not runtimes[j].allow_static and j not in plan.rests_in and not apart(*placed.bounds[name], placed.reaches[name], *placed.bounds[other.name], placed.reaches[other.name])
        )
        objects.append(CandidateObject(name, sizes, yaw, rotation, region, obstacles, toward, (lo, hi), reach))
        requires += [(index, _require_test(compiler, conditions[c.label_id], c.soft)) for c in plan.checks]
        requires += [(index, _outside_test(rule, name, decls, placed)) for rule in plan.exclusions]
        if region.tested is not None:
            requires.append((index, rows_test(region.tested.A, region.tested.b, name)))
        if region.kind in ("rectangle", "surface"):
            requires += [(index, inside_test(rule, rt, placed)) for rule in plan.rules if tested_not_cut(rule)]
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


def _rotation(rt: ObjectRuntime, compiler: CandidateCompiler) -> tuple[BatchValue | None, np.ndarray, BatchValue | None]:
    """(a random yaw, the rotation when fixed, the point it faces toward) of an object's candidates."""
    if rt.rotation is not None:
        return None, rt.rotation, None
    rule = rt.plan.orientation
    assert rule is not None
    if rule.kind not in ("facing", "facing toward"):
        raise Unbatchable(f"{rt.plan.name}'s `{rule.kind}` changes between scenes")
    value = compiler.compile(rule.arg)
    if rule.kind == "facing toward":
        if not value.vector:
            raise Unbatchable(f"{rt.plan.name} faces toward something that is not a point")
        return None, np.eye(3), value
    if value.vector:
        raise Unbatchable(f"{rt.plan.name} faces a direction that changes between scenes")
    return value, np.eye(3), None


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


def _outside_test(rule: Any, name: str, decls: dict[str, Any], placed: Placed) -> Test:
    """`reachable by R`'s excluded cell (the hole about R's base, or the gap) as a test: the
    candidate's centre outside the cell's interior, R's reach rows moved to each candidate's R."""
    robot = rule.args[0] if rule.args else None
    if rule.kind != "unreachable" or rule.soft is not None or not isinstance(robot, ir.ObjectRef) \
            or robot.name not in placed.bounds:
        raise Unbatchable(f"{name} has an excluded cell other than a placed robot's reach (`not visible from`)")
    decl = decls[robot.name]
    props = {key: value.value for key, value in decl.properties if isinstance(value, ir.Const)}
    ring, offset = local_ring(props, decl.class_name, robot.name, rule.span)
    a_local, b_local = ring.excluded()[rule.option("part")]

    def outside(state) -> np.ndarray:
        rotation, position = state.rotations[robot.name], state.positions[robot.name]
        base = position + np.einsum("nij,j->ni", rotation, offset)
        local = np.einsum("nji,nj->ni", rotation, state.positions[name] - base)  # R^T (p - base)
        # Inside the interior: strictly inside every row (the sampler keeps the boundary).
        return ~np.all(local @ a_local.T < b_local - 1e-9, axis=1)

    return outside


def _require_test(compiler: CandidateCompiler, condition: ir.Expr, soft: int | None) -> Test:
    value = compiler.compile(condition)
    if value.vector:
        raise Unbatchable("a require on a vector")
    fn = value.fn
    if soft is None:
        return lambda state: np.broadcast_to(fn(state)[:, 0] != 0.0, (len(state.keys),))
    return lambda state: (fn(state)[:, 0] != 0.0) | ~state.active[:, soft]  # type: ignore[index]
