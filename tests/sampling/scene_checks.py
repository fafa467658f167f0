"""An independent checker of sampled scenes: re-derives every relation of docs/language.md
(specifiers, requires, the workspace, collisions) from the scene JSON alone plus the
spec's relations as the IR states them. It counts what it checked and lists what it
could not evaluate; check_scenes fails on a relation never checked in any scene.

It shares no code with the sampler: no prsc.constraints, no prsc.geometry. Expressions
of the spec are evaluated in interval arithmetic (a random draw is the interval of its
possible values), so a relation with a random argument is checked for every value the
draw could have taken (`by (0.1, 0.2)` must hold with 0.1 at least; `at V((-1, 1), ...)`
must lie in the box). Rotations come from the JSON quaternions; the box-box test is an
own separating-axis test over all 15 axes.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from prsc.ir import model as ir
from prsc.ir.program import Program

TOL = 1e-9  # metres: every specifier and require holds to this
CONTACT = 1e-6  # boxes overlapping by less than this along some axis are in contact, not colliding


class Unknown(Exception):
    """The value cannot be derived from the scene JSON (then the relation is not checked)."""


class SceneCheck(list):
    """The violated relations of one scene (the list), plus what was checked and what could not be.

    `checked`: how many relations were evaluated; `unchecked`: the relations the checker
    could not evaluate in this scene, each with the reason.
    """

    def __init__(self) -> None:
        super().__init__()
        self.checked = 0
        self.unchecked: list[str] = []

    def tried(self, relation: str, check: Any) -> None:
        """Run one relation's check: `check()` returns a problem, or None when it holds."""
        try:
            bad = check()
        except Unknown as why:
            self.unchecked.append(f"{relation} ({why})")
            return
        self.checked += 1
        if bad:
            self.append(f"{relation}: {bad}")


# ---------------------------------------------------------------- intervals


@dataclass(frozen=True)
class Iv:
    """A scalar (shape ()) or vector (shape (3,)) interval [lo, hi]."""

    lo: np.ndarray
    hi: np.ndarray

    @staticmethod
    def exact(v: Any) -> Iv:
        a = np.asarray(v, dtype=float)
        return Iv(a, a)

    @property
    def is_vector(self) -> bool:
        return self.lo.shape == (3,)

    def __add__(self, o: Iv) -> Iv:
        return Iv(self.lo + o.lo, self.hi + o.hi)

    def __sub__(self, o: Iv) -> Iv:
        return Iv(self.lo - o.hi, self.hi - o.lo)

    def __neg__(self) -> Iv:
        return Iv(-self.hi, -self.lo)

    def __mul__(self, o: Iv) -> Iv:
        c = np.stack(np.broadcast_arrays(self.lo * o.lo, self.lo * o.hi, self.hi * o.lo, self.hi * o.hi))
        return Iv(c.min(axis=0), c.max(axis=0))

    def __truediv__(self, o: Iv) -> Iv:
        if np.any((o.lo <= 0) & (o.hi >= 0)):
            raise Unknown("division by an interval containing 0")
        return self * Iv(1.0 / o.hi, 1.0 / o.lo)

    def component(self, i: int) -> Iv:
        return Iv(self.lo[i], self.hi[i])

    def rotate(self, r: np.ndarray) -> Iv:
        mid, rad = (self.lo + self.hi) / 2, (self.hi - self.lo) / 2
        return Iv(r @ mid - np.abs(r) @ rad, r @ mid + np.abs(r) @ rad)

    def dot(self, n: np.ndarray) -> Iv:
        mid, rad = (self.lo + self.hi) / 2, (self.hi - self.lo) / 2
        return Iv(np.asarray(n @ mid - np.abs(n) @ rad), np.asarray(n @ mid + np.abs(n) @ rad))


def quat_matrix(q: list[float]) -> np.ndarray:
    """Rotation matrix of a unit quaternion [w, x, y, z]."""
    w, x, y, z = q
    n = math.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def euler_compat(a: float, b: float, c: float) -> np.ndarray:
    """docs/language.md section 1: Vector3D(a, b, c) = Rx(c) Ry(b) Rz(a)."""
    ca, sa, cb, sb, cc, sc = math.cos(a), math.sin(a), math.cos(b), math.sin(b), math.cos(c), math.sin(c)
    rz = np.array([[ca, -sa, 0], [sa, ca, 0], [0, 0, 1.0]])
    ry = np.array([[cb, 0, sb], [0, 1.0, 0], [-sb, 0, cb]])
    rx = np.array([[1.0, 0, 0], [0, cc, -sc], [0, sc, cc]])
    return rx @ ry @ rz


@dataclass
class Body:
    """An object of the scene JSON."""

    name: str
    p: np.ndarray
    r: np.ndarray
    dims: np.ndarray
    data: dict

    @property
    def half(self) -> np.ndarray:
        return self.dims / 2

    def s(self, n: np.ndarray) -> float:
        """Support (half-thickness) along n: sum h_i |n . R e_i|."""
        return float(np.abs(n @ self.r) @ self.half)

    def corners(self) -> np.ndarray:
        signs = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], dtype=float)
        return self.p + (signs * self.half) @ self.r.T


@dataclass(frozen=True)
class Point:
    """A face point: position and the frame of its object."""

    p: np.ndarray
    r: np.ndarray


@dataclass(frozen=True)
class Box:
    """A constant cuboid region (position, rotation, dims), or a planar rectangle (height 0)."""

    c: np.ndarray
    r: np.ndarray
    dims: np.ndarray
    planar: bool = False
    clearance: float | None = None  # a furniture board: free height above it


@dataclass(frozen=True)
class HalfSpace:
    point: np.ndarray
    normal: np.ndarray
    dist: float


_FACES = {"top": (2, 1), "bottom": (2, -1), "front": (1, 1), "back": (1, -1), "right": (0, 1), "left": (0, -1)}
_SIDES = {"left": (0, -1.0), "right": (0, 1.0), "ahead": (1, 1.0), "behind": (1, -1.0), "above": (2, 1.0), "below": (2, -1.0)}


class Evaluator:
    """Interval evaluation of IR expressions against one scene."""

    def __init__(self, program: Program, bodies: dict[str, Body]) -> None:
        self.program = program
        self.bodies = bodies
        self.variables = {v.name: v for v in program.variables}

    def ev(self, e: ir.Expr) -> Any:
        if isinstance(e, ir.Const):
            return Iv.exact(e.value) if isinstance(e.value, (int, float)) and not isinstance(e.value, bool) else e.value
        if isinstance(e, ir.VectorExpr):
            parts = [self.ev(c) for c in (e.x, e.y, e.z)]
            return Iv(np.array([p.lo for p in parts], dtype=float), np.array([p.hi for p in parts], dtype=float))
        if isinstance(e, ir.ListExpr):
            return [self.ev(i) for i in e.items]
        if isinstance(e, ir.ObjectRef):
            if e.name not in self.bodies:
                raise Unknown(f"object {e.name} not in the scene")
            return self.bodies[e.name]
        if isinstance(e, ir.VarRef):
            return self.ev(self.variables[e.name].value)
        if isinstance(e, ir.PropertyRef):
            return self.attr(self.ev(e.target), e.prop)
        if isinstance(e, ir.FacePoint):
            body = self.ev(e.target)
            off = np.zeros(3)
            for w in e.words:
                axis, sign = _FACES[w]
                off[axis] = sign * body.dims[axis] / 2
            return Point(body.p + body.r @ off, body.r)
        if isinstance(e, ir.RelativeTo):
            v, frame = self.vec(self.ev(e.value)), self.ev(e.frame)
            if isinstance(frame, (Body, Point)):
                return Iv.exact(frame.p) + v.rotate(frame.r)
            return self.vec(frame) + v
        if isinstance(e, ir.BinOp):
            a, b = self.num(self.ev(e.left)), self.num(self.ev(e.right))
            if e.op == "+":
                return a + b
            if e.op == "-":
                return a - b
            if e.op == "*":
                return a * b
            return a / b
        if isinstance(e, ir.UnaryOp):
            v = self.ev(e.operand)
            if e.op == "not":
                return None if v is None else (not v)
            return -self.num(v) if e.op == "-" else self.num(v)
        if isinstance(e, ir.Compare):
            return self.compare(e.op, self.ev(e.left), self.ev(e.right))
        if isinstance(e, ir.BoolOp):
            vals = [self.ev(o) for o in e.operands]
            if e.op == "and":
                return False if any(v is False for v in vals) else (True if all(v is True for v in vals) else None)
            return True if any(v is True for v in vals) else (False if all(v is False for v in vals) else None)
        if isinstance(e, ir.Call):
            args = [self.num(self.ev(a)) for a in e.args]
            if all(float(a.lo) == float(a.hi) for a in args):
                f = {"sin": math.sin, "cos": math.cos, "tan": math.tan, "sqrt": math.sqrt, "abs": abs, "min": min,
                     "max": max, "hypot": math.hypot, "atan2": math.atan2}[e.func]
                return Iv.exact(f(*[float(a.lo) for a in args]))
            raise Unknown("a function of a random value")
        if isinstance(e, ir.Distance):
            a, b = self.vec(self.ev(e.source)), self.vec(self.ev(e.target))
            if np.any(a.lo != a.hi) or np.any(b.lo != b.hi):
                raise Unknown("a distance to a random point")
            return Iv.exact(float(np.linalg.norm(a.lo - b.lo)))
        if isinstance(e, ir.Distribution):
            if e.kind == "range":
                lo, hi = self.num(self.ev(e.args[0])), self.num(self.ev(e.args[1]))
                return Iv(lo.lo, hi.hi)
            if e.kind == "truncnormal":
                lo, hi = self.num(self.ev(e.args[2])), self.num(self.ev(e.args[3]))
                return Iv(lo.lo, hi.hi)
            if e.kind in ("uniform", "discrete"):
                opts = [self.ev(a) for a in e.args]
                if all(isinstance(o, Iv) for o in opts):
                    return Iv(np.min([o.lo for o in opts], axis=0), np.max([o.hi for o in opts], axis=0))
            raise Unknown(f"a {e.kind} distribution")
        if isinstance(e, ir.RegionExpr):
            return self.region(e)
        if isinstance(e, ir.SurfaceRef):
            index = self.num(self.ev(e.index))
            if float(index.lo) != float(index.hi):
                raise Unknown("a random surface index")
            return furniture_surface(self.ev(e.target), e.name, int(index.lo))
        raise Unknown(type(e).__name__)

    def num(self, v: Any) -> Iv:
        if isinstance(v, Iv):
            return v
        if isinstance(v, (Point, Body)):
            return Iv.exact(v.p)
        raise Unknown(f"not a number or vector: {v!r}")

    def vec(self, v: Any) -> Iv:
        v = self.num(v)
        if not v.is_vector:
            raise Unknown("expected a vector")
        return v

    def attr(self, target: Any, prop: str) -> Any:
        if isinstance(target, Body):
            if prop == "position":
                return Iv.exact(target.p)
            if prop in ("x", "y", "z"):
                return Iv.exact(target.p["xyz".index(prop)])
            if prop in ("width", "length", "height"):
                return Iv.exact(target.dims[("width", "length", "height").index(prop)])
            raise Unknown(f"property {prop}")
        if isinstance(target, Point):
            if prop == "position":
                return Iv.exact(target.p)
            if prop in ("x", "y", "z"):
                return Iv.exact(target.p["xyz".index(prop)])
        if isinstance(target, Iv) and target.is_vector and prop in ("x", "y", "z"):
            return target.component("xyz".index(prop))
        raise Unknown(f"attribute {prop}")

    def compare(self, op: str, a: Any, b: Any) -> bool | None:
        a, b = self.num(a), self.num(b)
        if a.is_vector or b.is_vector:
            raise Unknown("vector comparison")
        if op in ("<", "<="):
            return True if a.hi <= b.lo + TOL else (False if a.lo > b.hi + TOL else None)
        if op in (">", ">="):
            return True if a.lo >= b.hi - TOL else (False if a.hi < b.lo - TOL else None)
        if op == "==":
            return True if (a.hi <= b.lo + TOL and a.lo >= b.hi - TOL) else (False if (a.lo > b.hi + TOL or a.hi < b.lo - TOL) else None)
        return None

    def const_vec(self, e: ir.Expr) -> np.ndarray:
        v = self.vec(self.ev(e))
        if np.any(v.lo != v.hi):
            raise Unknown("a random region")
        return v.lo

    def const_num(self, e: ir.Expr) -> float:
        v = self.num(self.ev(e))
        if v.is_vector or float(v.lo) != float(v.hi):
            raise Unknown("a random region size")
        return float(v.lo)

    def region(self, e: ir.RegionExpr) -> Any:
        a = dict(e.args)
        if e.kind in ("cuboid", "rectangle"):
            o = self.const_vec(a["orientation"])
            dims = [self.const_num(a["width"]), self.const_num(a["length"])]
            dims.append(self.const_num(a["height"]) if e.kind == "cuboid" else 0.0)
            return Box(self.const_vec(a["position"]), euler_compat(*o), np.array(dims), e.kind == "rectangle")
        if e.kind == "halfspace":
            dist = self.const_num(a["dist"]) if "dist" in a else 0.0
            n = self.const_vec(a["normal"])
            return HalfSpace(self.const_vec(a["point"]), n / np.linalg.norm(n), dist)
        if e.kind == "all":
            return "all"
        raise Unknown(f"region {e.kind}")


# ---------------------------------------------------------------- relations


def _box_inside(region: Any, body: Body, completely: bool) -> float:
    """How far (metres) the body (or its centre) sticks out of a region (<= 0: inside)."""
    points = body.corners() if completely else body.p[None, :]
    if region == "all":
        return -1.0
    if isinstance(region, Box):
        local = (points - region.c) @ region.r
        excess = np.abs(local) - region.dims / 2
        if region.planar:
            excess[:, 2] = np.abs(local[:, 2]) if not completely else 0.0
        return float(excess.max())
    if isinstance(region, HalfSpace):
        depth = (points - region.point) @ region.normal
        worst = float((-depth).max())
        if region.dist > 0:
            worst = max(worst, float((depth - region.dist).max()))
        return worst
    raise Unknown("region kind")


def sat_penetration(a: Body, b: Body) -> float:
    """Smallest overlap of the projections of two boxes over the 15 separating axes."""
    axes = [a.r[:, i] for i in range(3)] + [b.r[:, i] for i in range(3)]
    for i in range(3):
        for j in range(3):
            c = np.cross(a.r[:, i], b.r[:, j])
            n = np.linalg.norm(c)
            if n > 1e-9:
                axes.append(c / n)
    d = b.p - a.p
    return min(a.s(n) + b.s(n) - abs(float(n @ d)) for n in axes)


def _spec_text(spec: ir.Specifier) -> str:
    return f"{type(spec).__name__} at line {spec.span.line}"


def check_scene(program: Program, scene: dict) -> SceneCheck:
    """Every violated relation of one scene, as readable strings (empty when the scene is valid).

    A relation the checker cannot evaluate is not a violation, but it is listed in
    `unchecked`: check_scenes fails when a relation was never checked in any scene.
    """
    bodies = {
        o["name"]: Body(o["name"], np.array(o["position"], dtype=float), quat_matrix(o["quaternion"]),
                        np.array(o["dimensions"], dtype=float), o)
        for o in scene["objects"]
    }
    problems = SceneCheck()
    names = [o.name for o in program.objects]
    if sorted(names) != sorted(bodies):
        problems.append(f"objects differ: spec {sorted(names)} vs scene {sorted(bodies)}")
        return problems
    ev = Evaluator(program, bodies)
    for decl in program.objects:
        body = bodies[decl.name]
        for prop, idx in (("width", 0), ("length", 1), ("height", 2)):
            expr = decl.prop(prop)
            if expr is not None:
                problems.tried(f"{decl.name}: {prop}", lambda: _dimension(ev, body, expr, prop, idx))
        for spec in decl.specifiers:
            if isinstance(spec, ir.With) and spec.prop not in ("position", "orientation"):
                continue  # a property value, not a relation (sizes are checked above)
            problems.tried(f"{decl.name}: {_spec_text(spec)}", lambda: _check_specifier(ev, body, spec))
    # Requires (hard ones).
    for req in program.requires:
        if req.probability < 1.0:
            continue
        problems.tried(f"require at line {req.span.line}", lambda: "violated" if ev.ev(req.condition) is False else None)
    # Workspace containment.
    if program.workspace is not None:
        for body in bodies.values():
            problems.tried(f"{body.name}: workspace", lambda: _workspace(ev, program.workspace, body))
    # Collisions.
    allowed = {n for n, b in bodies.items() if b.data.get("properties", {}).get("allowCollisions")}
    # An object `on` a container rests inside the container's box: its walls bound it (above).
    inside = {
        frozenset((decl.name, spec.target.name))
        for decl in program.objects for spec in decl.specifiers
        if isinstance(spec, ir.On) and isinstance(spec.target, ir.ObjectRef)
        and container_interior(bodies[spec.target.name], spec.completely or getattr(spec, "inside", False)) is not None
    }
    # An object on a furniture board stands inside the furniture's box, between its parts.
    inside |= {
        frozenset((decl.name, spec.target.target.name))
        for decl in program.objects for spec in decl.specifiers
        if isinstance(spec, (ir.On, ir.StablyOn)) and isinstance(spec.target, ir.SurfaceRef)
        and isinstance(spec.target.target, ir.ObjectRef)
    }
    items = list(bodies.values())
    for i, a in enumerate(items):
        for b in items[:i]:
            if a.name in allowed or b.name in allowed or frozenset((a.name, b.name)) in inside:
                continue
            ra = np.abs(a.r) @ a.half
            rb = np.abs(b.r) @ b.half
            if np.any(np.abs(a.p - b.p) >= ra + rb):
                problems.checked += 1  # apart along a world axis: checked, no collision
                continue
            problems.checked += 1
            pen = sat_penetration(a, b)
            if pen > CONTACT:
                problems.append(f"{a.name} and {b.name} intersect (overlap {pen:.3g} m)")
    return problems


def check_scenes(program: Program, scenes: Any) -> SceneCheck:
    """check_scene over several scenes (problems prefixed by the scene's index); a relation
    not checked in any of them is a problem too (so a spec the checker cannot read fails)."""
    total = SceneCheck()
    never: list[str] | None = None
    for index, scene in enumerate(scenes):
        one = check_scene(program, scene)
        total.extend(f"scene {index}: {p}" for p in one)
        total.checked += one.checked
        names = [u.split(" (")[0] for u in one.unchecked]
        never = names if never is None else [n for n in never if n in names]
        total.unchecked.extend(one.unchecked)
    total.extend(f"never checked: {n}" for n in (never or []))
    return total


def _dimension(ev: Evaluator, body: Body, expr: ir.Expr, prop: str, idx: int) -> str | None:
    v = ev.num(ev.ev(expr))
    if not (v.lo - TOL <= body.dims[idx] <= v.hi + TOL):
        return f"{body.dims[idx]} not in [{v.lo}, {v.hi}]"
    return None


def _workspace(ev: Evaluator, workspace: ir.Expr, body: Body) -> str | None:
    out = _box_inside(ev.ev(workspace), body, True)
    return f"sticks out of the workspace by {out:.3g} m" if out > TOL else None


def _clamp(value: float, low: float, high: float) -> float:
    return max(low, min(high, value))


# The container assets' own floors and walls (docs/backends.md, "Container assets"): the
# interior `completely on` uses when the class declares none.
ASSET_INTERIORS = {
    "tray": lambda w, l, h: ("box", _clamp(0.2 * h, 0.005, 0.015), _clamp(0.04 * min(w, l), 0.003, 0.012)),
    "bin": lambda w, l, h: ("box", _clamp(0.05 * h, 0.005, 0.015), _clamp(0.03 * min(w, l), 0.004, 0.015)),
    "box": lambda w, l, h: ("box", *(_clamp(0.02 * min(w, l), 0.003, 0.01),) * 2),
    "bowl": lambda w, l, h: ("round", max(0.15 * h, 0.002), max(0.06 * min(w, l) / 2, 0.002)),
    "cup": lambda w, l, h: ("round", max(0.08 * h, 0.002), max(0.08 * min(w, l) / 2, 0.002)),
    "bucket": lambda w, l, h: ("round", max(0.05 * h, 0.002), max(0.04 * min(w, l) / 2, 0.002)),
    "plate": lambda w, l, h: ("round", max(0.4 * h, 0.002), max(0.05 * min(w, l) / 2, 0.002)),
}


def container_interior(target: Body, completely: bool = False) -> tuple[float, list[tuple[np.ndarray, float]]] | None:
    """A container's floor top (above its centre) and interior edges (local normal, offset):
    the declared one, or for `completely on` the container asset's own.

    Written from docs/language.md "Containers", apart from prsc's own code: floor at most
    half the height; walls at most a quarter of the short side, or 0.3 of a round one's
    radius, whose interior is the 16-gon of its wall slabs' inner faces."""
    props = target.data.get("properties", {})
    if "floorThickness" not in props:
        recipe = ASSET_INTERIORS.get(target.data.get("model") or "") if completely else None
        if recipe is None:
            return None
        shape, floor, wall = recipe(*(float(v) for v in target.dims))
        props = {"container": shape, "floorThickness": floor, "wallThickness": wall}
    w, l, h = (float(v) for v in target.dims)
    if props["container"] == "round":
        radius = min(w, l) / 2
        wall = min(float(props["wallThickness"]), 0.3 * radius)
        edges = [(np.array([math.cos(2 * math.pi * k / 16), math.sin(2 * math.pi * k / 16)]), radius - wall) for k in range(16)]
    else:
        wall = min(float(props["wallThickness"]), 0.25 * min(w, l))
        edges = [(np.array(m, dtype=float), c) for m, c in
                 (((1, 0), w / 2 - wall), ((-1, 0), w / 2 - wall), ((0, 1), l / 2 - wall), ((0, -1), l / 2 - wall))]
    return -h / 2 + min(float(props["floorThickness"]), h / 2), edges


def furniture_surface(target: Any, name: str, index: int) -> Box:
    """Board `index` of a shelf (or a table's top), from docs/language.md "Support surfaces":
    panels of thickness t = 2.5% of the short side in [12 mm, 30 mm] (at most 20% of it), four
    boards with centres at -h/2 + t/2 + k (h - t) / 3, each between the sides and in front of the back."""
    if not isinstance(target, Body):
        raise Unknown("a surface of a non-object")
    w, l, h = (float(v) for v in target.dims)
    model = target.data.get("model")
    if model == "table" and name == "tabletop" and index == 0:
        return Box(target.p + target.r @ np.array([0.0, 0.0, h / 2]), target.r, np.array([w, l, 0.0]), True)
    if model != "shelf" or name != "boards":
        raise Unknown(f"surface {name} of model {model}")
    t = min(max(0.025 * min(w, l), 0.012), 0.03, 0.2 * min(w, l))
    centres = [-h / 2 + t / 2 + k * (h - t) / 3 for k in range(4)]
    top = centres[index] + t / 2
    clearance = centres[index + 1] - t / 2 - top if index < 3 else None
    return Box(target.p + target.r @ np.array([0.0, t / 2, top]), target.r, np.array([w - 2 * t, l - t, 0.0]), True, clearance)


def _on_floor(body: Body, target: Body, completely: bool, inside: bool = False) -> str | None:
    """`on X` for a container X: resting on its floor, centre (footprint) inside its walls."""
    floor_top, edges = container_interior(target, completely or inside)  # type: ignore[misc]
    n = target.r[:, 2]
    gap = float(n @ (body.p - target.p)) - floor_top - body.s(n)
    if abs(gap) > TOL:
        return f"not resting on the floor of {target.name} (gap {gap:.3g})"
    for m, c in edges:
        a = m[0] * target.r[:, 0] + m[1] * target.r[:, 1]
        if float(a @ (body.p - target.p)) > c - (body.s(a) if completely else 0.0) + TOL:
            return f"outside the interior of {target.name}"
    return None


def _check_specifier(ev: Evaluator, body: Body, spec: ir.Specifier) -> str | None:
    """A description of how the body violates one specifier, or None."""
    p = body.p
    if isinstance(spec, ir.At) or (isinstance(spec, ir.With) and spec.prop == "position"):
        v = ev.vec(ev.ev(spec.point if isinstance(spec, ir.At) else spec.value))
        if np.any(p < v.lo - TOL) or np.any(p > v.hi + TOL):
            return f"position {p} not at {v.lo}..{v.hi}"
        return None
    if isinstance(spec, ir.StablyOn):
        problem = _check_specifier(ev, body, ir.On(spec.span, spec.sets, spec.reads, spec.target, False))
        return problem or _centre_of_mass_supported(ev, body, spec)
    if isinstance(spec, ir.VisibleFrom):
        camera = ev.ev(spec.camera)
        if not isinstance(camera, Body):
            raise Unknown("visible from a non-object")
        worst = _view_excess(camera, body)
        if getattr(spec, "outside", False):  # `not visible from C`: some corner out of the view
            return None if worst >= -TOL else f"wholly inside the view of {camera.name} (by {-worst:.3g})"
        return None if worst <= TOL else f"outside the view of {camera.name} by {worst:.3g}"
    if isinstance(spec, ir.On):
        target = ev.ev(spec.target)
        inside = getattr(spec, "inside", False)
        if isinstance(target, Body) and container_interior(target, spec.completely or inside) is not None:
            return _on_floor(body, target, spec.completely, inside)
        if isinstance(target, Body) and inside:
            return f"{target.name} is no container"
        if isinstance(target, Body):
            n, u, v = target.r[:, 2], target.r[:, 0], target.r[:, 1]
            top = target.p + n * target.dims[2] / 2
            gap = float(n @ (p - top)) - body.s(n)
            if abs(gap) > TOL:
                return f"not resting on {target.name} (gap {gap:.3g})"
            for axis, half in ((u, target.dims[0] / 2), (v, target.dims[1] / 2)):
                limit = half - (body.s(axis) if spec.completely else 0.0)
                if abs(float(axis @ (p - top))) > limit + TOL:
                    return f"outside the top of {target.name} along {axis}"
            return None
        if isinstance(target, Box) and target.planar:
            n = target.r[:, 2] if target.r[2, 2] >= 0 else -target.r[:, 2]
            gap = float(n @ (p - target.c)) - body.s(n)
            if abs(gap) > TOL:
                return f"not resting on the surface (gap {gap:.3g})"
            proj = p - body.s(n) * n
            local = (proj - target.c) @ target.r
            for i in (0, 1):
                axis = target.r[:, i]
                limit = target.dims[i] / 2 - (body.s(axis) if spec.completely else 0.0)
                if abs(local[i]) > limit + TOL:
                    return "outside the surface"
            if target.clearance is not None and 2 * body.s(n) > target.clearance + TOL:
                return "taller than the free height above the board"
            return None
        point = ev.vec(target if isinstance(target, Iv) else Iv.exact(target.p))
        want = point + Iv.exact(np.array([0.0, 0.0, body.s(np.array([0.0, 0.0, 1.0]))]))
        if np.any(p < want.lo - TOL) or np.any(p > want.hi + TOL):
            return f"not on the point {want.lo}"
        return None
    if isinstance(spec, ir.Direction):
        target = ev.ev(spec.target)
        axis, sign = _SIDES[spec.relation]
        if isinstance(target, (Body, Point)):
            n, c = sign * target.r[:, axis], target.p
            cn = float(n @ c)
        else:
            n = np.zeros(3)
            n[axis] = sign
            cv = ev.vec(target).dot(n)
            cn = float(cv.hi)  # the worst case of a random point
        d = 0.0 if spec.by is None else float(ev.num(ev.ev(spec.by)).lo)
        margin = float(n @ p) - cn - d - body.s(n)
        if margin < -TOL:
            return f"{spec.relation} violated by {-margin:.3g} m"
        if spec.up_to is not None:  # `by (low, high)`: the gap is at most high
            nearest = cn if isinstance(target, (Body, Point)) else float(cv.lo)
            over = float(n @ p) - nearest - body.s(n) - float(ev.num(ev.ev(spec.up_to)).hi)
            if over > TOL:
                return f"{spec.relation} gap {over:.3g} m more than its greatest value"
        return None
    if isinstance(spec, ir.AlignedWith):
        target = ev.ev(spec.target)
        i = "xyz".index(spec.axis.strip("'\"").lower())
        val = Iv.exact(target.p[i]) if isinstance(target, (Body, Point)) else ev.vec(target).component(i)
        if p[i] < float(val.lo) - TOL or p[i] > float(val.hi) + TOL:
            return f"not aligned on {spec.axis}"
        return None
    if isinstance(spec, ir.In):
        region = ev.ev(spec.region)
        out = _box_inside(region, body, spec.completely)
        if out > TOL:
            return f"outside its region by {out:.3g} m"
        return None
    if isinstance(spec, ir.Beyond):
        x = ev.vec(ev.num(ev.ev(spec.target)))
        o = ev.vec(ev.num(ev.ev(spec.origin)))
        by = ev.num(ev.ev(spec.by))
        if np.any(x.lo != x.hi) or np.any(o.lo != o.hi) or np.any(by.lo != by.hi):
            raise Unknown("random beyond")
        x, o = x.lo, o.lo
        if by.is_vector:
            f = np.array([x[0] - o[0], x[1] - o[1], 0.0])
            y = f / np.linalg.norm(f)
            xa = np.cross(y, [0.0, 0.0, 1.0])
            want = x + by.lo[0] * xa + by.lo[1] * y + by.lo[2] * np.array([0.0, 0.0, 1.0])
        else:
            want = x + float(by.lo) * (x - o) / np.linalg.norm(x - o)
        if np.max(np.abs(p - want)) > TOL:
            return f"not at {want}"
        return None
    if isinstance(spec, ir.Facing):
        v = ev.num(ev.ev(spec.direction))
        forward = body.r[:, 1]
        if not v.is_vector and np.any(v.lo != v.hi):
            # A random yaw: yaw only, and the angle within the interval of the draw.
            yaw = math.atan2(-forward[0], forward[1])
            lo, hi = float(v.lo), float(v.hi)
            offset = (yaw - lo) % (2 * math.pi)
            if abs(body.r[2, 2] - 1.0) > 1e-9 or (offset > hi - lo + 1e-9 and offset < 2 * math.pi - 1e-9):
                return f"yaw {yaw:.6g} not in [{lo:.6g}, {hi:.6g}]"
            return None
        if np.any(v.lo != v.hi):
            raise Unknown("random facing direction")
        if v.is_vector:
            want = v.lo / np.linalg.norm(v.lo)
            if np.max(np.abs(forward - want)) > 1e-9:
                return f"faces {forward}, not {want}"
        else:
            yaw = float(v.lo)
            want = np.array([-math.sin(yaw), math.cos(yaw), 0.0])
            if np.max(np.abs(forward - want)) > 1e-9 or abs(body.r[2, 2] - 1.0) > 1e-9:
                return f"yaw differs from {yaw}"
        return None
    if isinstance(spec, ir.With) and spec.prop == "orientation":
        v = ev.num(ev.ev(spec.value))
        if np.any(v.lo != v.hi):
            raise Unknown("random orientation")
        want = euler_compat(*v.lo) if v.is_vector else euler_compat(float(v.lo), 0.0, 0.0)
        if np.max(np.abs(body.r - want)) > 1e-9:
            return "orientation differs from its Euler angles"
        return None
    if isinstance(spec, ir.FacingToward):
        target = ev.num(ev.ev(spec.target))
        if np.any(target.lo != target.hi):
            raise Unknown("random target")
        d = target.lo - p
        d[2] = 0.0
        if np.linalg.norm(d) < 1e-12:
            return None
        forward = body.r[:, 1]
        if abs(body.r[2, 2] - 1.0) > 1e-9 or np.max(np.abs(forward - d / np.linalg.norm(d))) > 1e-9:
            return "does not face toward its target"
        return None
    if isinstance(spec, ir.ReachableBy):
        robot = ev.ev(spec.robot)
        if not isinstance(robot, Body):
            raise Unknown("reachable by a non-object")
        return _outside_reach(robot, p)
    raise Unknown(f"the checker has no test for {type(spec).__name__}")


def _mass(body: Body) -> float:
    """The scene JSON's mass (the centre of mass taken at the box centre)."""
    return float(body.data["mass"])


def _centre_of_mass_supported(ev: Evaluator, body: Body, spec: ir.StablyOn) -> str | None:
    """docs/language.md "`stably on X`": for each support under the target (X stably on Y, ...), the
    centre of mass of the body and the objects between lies over that support's top face and
    the footprint of the object standing on it."""
    decls = {d.name: d for d in ev.program.objects}
    carried = [body]
    target = spec.target
    while isinstance(target, ir.ObjectRef) and len(carried) <= len(decls):
        above = ev.bodies[target.name]
        carried.append(above)
        below = next((s.target for s in decls[target.name].specifiers if isinstance(s, ir.StablyOn)), None)
        if not isinstance(below, ir.ObjectRef):
            return None
        support = ev.bodies[below.name]
        masses = np.array([_mass(b) for b in carried])
        com = (masses[:, None] * np.array([b.p for b in carried])).sum(axis=0) / masses.sum()
        for face in (support, above):  # over the contact: below's top face and above's footprint
            local = face.r.T @ (com - face.p)
            if abs(local[0]) > face.dims[0] / 2 + TOL or abs(local[1]) > face.dims[1] / 2 + TOL:
                return f"the centre of mass over {below.name} lies outside its contact with {above.name}"
        target = below
    return None


def _view_excess(camera: Body, body: Body) -> float:
    """How far the box's worst corner lies out of the camera's view (<= 0: wholly inside).

    docs/language.md "`visible from C`": every corner in front of the camera's box, within the far
    plane (the camera's `far`, else 3 m) and inside the image's edges (fovy, resolution)."""
    info = camera.data.get("camera")
    if not info:
        raise Unknown(f"{camera.name} is not a camera")
    far = float(camera.data.get("properties", {}).get("far", 3.0))
    tan_z = math.tan(math.radians(float(info["fovy"])) / 2)
    width, height = info["resolution"]
    tan_x = tan_z * width / height
    local = (body.corners() - camera.p) @ camera.r
    x, y, z = local[:, 0], local[:, 1], local[:, 2]
    worst = max(float((camera.dims[1] / 2 - y).max()), float((y - far).max()),
                float((np.abs(x) - y * tan_x).max()), float((np.abs(z) - y * tan_z).max()))
    return worst


def _outside_reach(robot: Body, p: np.ndarray) -> str | None:
    """Whether p is in the robot's reachable ring (the outer cell, out of the hole and the gap),
    as the ring's own file in the build folder holds it, about the root the scene mounts."""
    from prsc.constraints.arm_reach import arm_reach, reach_cache
    from prsc.user_assets.asset_files import model_asset, names_asset

    model = robot.data.get("model")
    properties = robot.data.get("properties", {})
    if not names_asset(model) or "rootOffset" not in properties:
        raise Unknown(f"no reach for model {model!r}")
    asset = model_asset(model)
    if properties.get("tcp") not in (None, asset.tcp):
        raise Unknown(f"{robot.name}'s tool is not its file's")
    arm_reach(asset)  # built (or read) once: the checks read its file
    ring = json.loads(reach_cache(asset).read_text(encoding="utf-8"))
    local = robot.r.T @ (p - (robot.p + robot.r @ np.asarray(properties["rootOffset"])))
    outside = float(np.max(np.array(ring["A"]) @ local - np.array(ring["b"])))
    # Inside an excluded cell by its least depth: every row holds with room to spare.
    inside = [float(np.min(np.array(ring[key + "_b"]) - np.array(ring[key + "_A"]) @ local)) for key in ("hole", "gap")]
    worst = max([outside] + inside)
    return None if worst <= TOL else f"outside {robot.name}'s reach by {worst:.3g} m"
