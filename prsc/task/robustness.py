"""One evaluator of task expressions on a world state: each predicate's truth and robustness in
metres, the signed distance to where its truth changes (docs/tasks.md)."""

from __future__ import annotations

import math
import operator
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from prsc.task.task_regions import (box_corners, box_region, point_polygon_distance, polygon_signed_distance,
                               prepared_polygon, prism_signed_distance)
from prsc.task.terms import DIRECTIONS, Task, TaskObject, Term
from prsc.task.world import Pose, WorldState

REST_SPEED = 0.005  # m/s: `at rest` below this linear speed
REST_ANGULAR = 0.05  # rad/s: and below this angular speed
UPRIGHT_ANGLE = math.radians(10.0)  # `upright`: its up axis within this of world z
ON_GAP = 0.01  # m: `on` rests on the surface within this


class Truth(NamedTuple):
    """A predicate's value: whether it holds, and its robustness (positive where it holds). (Immutable.)"""

    holds: bool
    robustness: float


def support_along(half: np.ndarray, pose: Pose, n: np.ndarray) -> float:
    """s(n): the box's half-thickness (half extents `half`) along unit n (docs/language.md, Specifiers)."""
    return float(half @ np.abs(pose.rotation.T @ n))


def _norm(v: np.ndarray) -> float:
    x, y, z = v.tolist()
    return math.sqrt(x * x + y * y + z * z)


def _local(pose: Pose, points: np.ndarray) -> np.ndarray:
    return (points - pose.position) @ pose.rotation


class Evaluator:
    """Evaluates the terms of one compiled task on world states."""

    def __init__(self, task: Task):
        self.task = task
        self.objects = {o.name: o for o in task.objects}
        self._corners = {o.name: box_corners(o.dimensions) for o in task.objects}
        self._half = {o.name: np.asarray(o.dimensions, dtype=float) / 2 for o in task.objects}
        self._radius = {name: _norm(half) for name, half in self._half.items()}  # centre to corner
        self._boxes = {o.name: box_region(o.dimensions) for o in task.objects}
        self._supports = {o.name: prepared_polygon(o.support) for o in task.objects}
        self._interiors = {o.name: prepared_polygon(o.interior) for o in task.objects if o.interior is not None}
        self._compiled: dict[int, tuple[Term, Callable[[WorldState], object]]] = {}
        self._static = frozenset(o.name for o in task.objects if o.static)

    # ------------------------------------------------------------ values
    # Each term is turned once into a closure over its children (evaluated at every control step).

    def value(self, term: Term, world: WorldState):
        """A term's value: Truth for a predicate, else a float or a vector (numpy, 3)."""
        return self.compiled(term)(world)

    def truth(self, term: Term, world: WorldState) -> Truth:
        """A predicate's truth and robustness."""
        return self.compiled(term)(world)

    def compiled(self, term: Term) -> Callable[[WorldState], object]:
        """The term as a function of the world state (made once per term)."""
        found = self._compiled.get(id(term))
        if found is None or found[0] is not term:
            found = self._compiled[id(term)] = (term, self._compile(term))
        return found[1]

    def _compile(self, term: Term) -> Callable[[WorldState], object]:
        function = self._compile_term(term)
        return _once(function) if term.op != "const" and self._episode_constant(term) else function

    def _episode_constant(self, term: Term) -> bool:
        """Whether a number or vector term reads only constants and static objects' poses and sizes,
        which do not move during an episode (`table.z + table.height / 2`): its value is read once."""
        if term.op == "object":
            return term.name in self._static
        if term.is_predicate or term.op == "link" or (term.op == "attr" and term.name == "speed"):
            return False
        return all(self._episode_constant(a) for a in term.args)

    def _compile_term(self, term: Term) -> Callable[[WorldState], object]:
        op, args, name = term.op, term.args, term.name
        children = [self.compiled(a) for a in args]
        if op == "const":
            value = float(term.value)  # type: ignore[arg-type]
            return lambda w: value
        if op == "true":
            return lambda w: Truth(True, math.inf)
        if op in ("object", "link"):
            key = term.key
            return lambda w: w.poses[key].position
        if op == "attr":
            return self._compile_attribute(term, children[0])
        if op == "vector":
            return lambda w: np.array([_as_number(f(w)) for f in children])
        if op == "neg":
            inner = children[0]
            return lambda w: -inner(w)
        if op == "arith":
            left, right = children
            combine = {"+": operator.add, "-": operator.sub, "*": operator.mul, "/": operator.truediv}[name]  # type: ignore[index]
            return lambda w: combine(left(w), right(w))
        if op == "distance":
            first, second = children
            return lambda w: _norm(np.asarray(first(w), dtype=float) - np.asarray(second(w), dtype=float))
        if op in ("and", "or") and len(children) == 2:  # the common case, without the lists (every control step)
            first, second = children
            if op == "and":
                def both(w):
                    a, b = first(w), second(w)
                    return Truth(bool(a.holds and b.holds), min(a.robustness, b.robustness))
                return both

            def either(w):
                a, b = first(w), second(w)
                return Truth(bool(a.holds or b.holds), max(a.robustness, b.robustness))
            return either
        if op == "and":
            def conjunction(w):
                parts = [f(w) for f in children]
                return Truth(all(p.holds for p in parts), min(p.robustness for p in parts))
            return conjunction
        if op == "or":
            def disjunction(w):
                parts = [f(w) for f in children]
                return Truth(any(p.holds for p in parts), max(p.robustness for p in parts))
            return disjunction
        if op == "not":
            inner = children[0]

            def negation(w):
                value = inner(w)
                return Truth(not value.holds, -value.robustness)
            return negation
        if op == "compare":
            first, second = children
            return lambda w: _compare(name, _as_number(first(w)), _as_number(second(w)))  # type: ignore[arg-type]
        if term.is_predicate:
            measure = self._relation(term)

            def relation(w):
                rho = measure(w)
                return Truth(rho >= 0.0, rho)
            return relation
        raise ValueError(f"unknown task term {op!r}")

    def _compile_attribute(self, term: Term, target: Callable[[WorldState], object]) -> Callable[[WorldState], object]:
        attribute, of = term.name, term.args[0]
        if of.op == "object":
            obj = of.name
            if attribute == "position":
                return lambda w: w.poses[obj].position
            if attribute == "speed":
                return lambda w: _norm(w.poses[obj].linear)
            if attribute in ("width", "length", "height"):
                size = self.objects[obj].dimensions[("width", "length", "height").index(attribute)]  # type: ignore[index]
                return lambda w: size
        axis = "xyz".index(attribute)  # type: ignore[arg-type]
        return lambda w: float(target(w)[axis])  # type: ignore[index]

    # ------------------------------------------------------------ predicates

    def robustness(self, term: Term, world: WorldState) -> float:
        """The robustness of a relation or state word (it holds where it is >= 0)."""
        return self._relation(term)(world)

    def _relation(self, term: Term) -> Callable[[WorldState], float]:
        """A relation's robustness as a function of the world state, its objects bound once."""
        op = term.op
        name = term.args[0].key
        if op == "touches":
            other = term.args[1].key
            return lambda w: -w.distance(name, other)  # type: ignore[arg-type]
        obj = self.objects[name]  # type: ignore[index]
        if op in ("in", "on"):
            return self._containment(op, term.completely, obj, self.objects[term.args[1].key])  # type: ignore[index]
        if op in DIRECTIONS:
            other, axis, half = term.args[1].key, np.asarray(DIRECTIONS[op]), self._half[name]  # type: ignore[index]
            by = self.compiled(term.args[2]) if len(term.args) > 2 else (lambda w: 0.0)

            def direction(w):
                pose, target = w.poses[name], w.poses[other]
                n = target.rotation @ axis
                return float(n @ (pose.position - target.position)) - _as_number(by(w)) - support_along(half, pose, n)
            return direction
        if op == "at_rest":
            radius = self._radius[name]  # type: ignore[index]

            def at_rest(w):
                pose = w.poses[name]
                return min(REST_SPEED - _norm(pose.linear), radius * (REST_ANGULAR - _norm(pose.angular)))
            return at_rest
        if op == "upright":
            return lambda w: UPRIGHT_ANGLE - math.acos(min(1.0, max(-1.0, float(w.poses[name].rotation[2, 2]))))
        if op == "holds":
            held = term.args[1].name
            return lambda w: self._holds(obj, held, w)  # type: ignore[arg-type]
        if op == "visible":
            camera = self.objects[term.args[1].name]  # type: ignore[index]
            return lambda w: self._visible(obj, w.poses[name], camera, w.poses[camera.name])
        raise ValueError(f"unknown task relation {op!r}")

    def _containment(self, op: str, completely: bool, obj: TaskObject, target: TaskObject) -> Callable[[WorldState], float]:
        name, target_name = obj.name, target.name
        if op == "in" and not rests_in(target):
            corners, box = self._corners[name], self._boxes[target_name]

            def inside(w):
                pose, target_pose = w.poses[name], w.poses[target_name]
                points = (pose.position + corners @ pose.rotation.T) if completely else pose.position[None]
                return float(prism_signed_distance(box, _local(target_pose, points)).min())
            return inside
        # `in` a link rests on its interior's floor, `on` it (and in or on a container) on its support surface
        region, footprint = ((target.interior, self._interiors[target_name]) if op == "in" and target.interior is not None
                             else (target.support, self._supports[target_name]))
        high, (hx, hy, hz) = region.high, self._half[name].tolist()
        corners = self._corners[name]

        def resting(w):
            # min(ON_GAP - |gap|, the footprint's signed distance, -distance(obj, target)), in floats:
            # this runs at every control step (docs/tasks.md, Cost)
            pose, target_pose = w.poses[name], w.poses[target_name]
            (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = target_pose.rotation.tolist()
            px, py, pz = pose.position.tolist()
            tx, ty, tz = target_pose.position.tolist()
            dx, dy, dz = px - tx, py - ty, pz - tz
            (o00, o01, o02), (o10, o11, o12), (o20, o21, o22) = pose.rotation.tolist()
            # the object's half-thickness along the target's up axis (r02, r12, r22): support_along
            thickness = (hx * abs(o00 * r02 + o10 * r12 + o20 * r22) + hy * abs(o01 * r02 + o11 * r12 + o21 * r22)
                         + hz * abs(o02 * r02 + o12 * r12 + o22 * r22))
            gap = r02 * dx + r12 * dy + r22 * dz - high - thickness
            if completely:
                local = _local(target_pose, pose.position + corners @ pose.rotation.T)
                over = float(polygon_signed_distance(footprint, local[:, :2]).min())
            else:
                over = point_polygon_distance(footprint, r00 * dx + r10 * dy + r20 * dz, r01 * dx + r11 * dy + r21 * dz)
            near = min(ON_GAP - abs(gap), over)
            # Touching the target only decides the minimum when it is further than -near: the distance
            # function may stop as soon as it shows it is not (prsc/task/world.py, DistanceFn).
            return min(near, -w.distance(name, target_name, -near))
        return resting

    def _holds(self, robot: TaskObject, held: str, world: WorldState) -> float:
        if len(robot.fingers) < 2:
            raise ValueError(f"{robot.name} has no gripper with two finger links")
        grip = [-world.distance(f"{robot.name}/{finger}", held) for finger in robot.fingers]
        first, second = sorted(grip, reverse=True)[:2]
        apart = [world.distance(held, other.name) for other in self.task.bodies()
                 if other.name not in (robot.name, held) and other.camera is None]
        return min([first, second] + apart)

    def _visible(self, obj: TaskObject, pose: Pose, camera: TaskObject, camera_pose: Pose) -> float:
        fovy, aspect = camera.camera  # type: ignore[misc]
        tan_y = math.tan(math.radians(fovy) / 2)
        tan_x = tan_y * aspect
        corners = _local(camera_pose, pose.position + self._corners[obj.name] @ pose.rotation.T)
        x, y, z = corners[:, 0], corners[:, 1], corners[:, 2]  # the camera looks along its +y, up +z
        margins = np.stack([(tan_x * y - x) / math.hypot(1, tan_x), (tan_x * y + x) / math.hypot(1, tan_x),
                            (tan_y * y - z) / math.hypot(1, tan_y), (tan_y * y + z) / math.hypot(1, tan_y), y])
        return float(margins.min())


def _once(function: Callable[[WorldState], object]) -> Callable[[WorldState], object]:
    """`function`'s value at the first state it is asked about, at every later state."""
    kept: list = []

    def constant(w):
        if kept:
            return kept[0]
        kept.append(function(w))
        return kept[0]
    return constant


def every_term(task: Task) -> list[Term]:
    """Every term of every statement, children before their parents."""
    out: list[Term] = []

    def walk(term: Term) -> None:
        for arg in term.args:
            walk(arg)
        out.append(term)

    s = task.statements
    for statement in (*s.goals, *s.failures, *s.records):
        walk(statement.expr)
    return out


def velocity_objects(task: Task) -> frozenset[str]:
    """The objects whose velocities the task reads (`at rest`, `.speed`)."""
    return frozenset(t.args[0].name for t in every_term(task)  # type: ignore[misc]
                     if t.op == "at_rest" or (t.op == "attr" and t.name == "speed" and t.args[0].op == "object"))


def distance_pairs(task: Task) -> list[tuple[str, str]]:
    """The (object or link, object) pairs whose distance the task reads at every step."""
    objects = {o.name: o for o in task.objects}
    out: list[tuple[str, str]] = []
    for term in every_term(task):
        names = [a.key for a in term.args if a.op in ("object", "link")]
        if term.op == "touches" or term.op == "on" or (term.op == "in" and rests_in(objects[names[1]])):  # type: ignore[index]
            out.append((names[0], names[1]))  # type: ignore[arg-type]
        elif term.op == "holds":
            robot, held = objects[names[0]], names[1]  # type: ignore[index]
            out.extend((f"{robot.name}/{finger}", held) for finger in robot.fingers)  # type: ignore[misc]
            out.extend((held, other.name) for other in task.bodies()  # type: ignore[misc]
                       if other.name not in (robot.name, held) and other.camera is None)
    return out


def rests_in(target: TaskObject) -> bool:
    """Whether `in` the target means resting on a floor within walls (a container, a hollow link),
    rather than the centre inside its box."""
    return target.container or target.interior is not None


def _as_number(value) -> float:
    return float(value.robustness if isinstance(value, Truth) else value)


def _compare(op: str, a: float, b: float) -> Truth:
    if op in ("<", "<="):
        return Truth(a < b if op == "<" else a <= b, b - a)
    if op in (">", ">="):
        return Truth(a > b if op == ">" else a >= b, a - b)
    if op == "==":
        return Truth(a == b, -abs(a - b))
    return Truth(a != b, abs(a - b))


def json_value(value) -> object:
    """A term's value as JSON data (a record): a bool, a number or a list."""
    if isinstance(value, Truth):
        return value.holds
    if isinstance(value, np.ndarray):
        return [float(v) for v in value]
    return float(value)
