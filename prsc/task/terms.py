"""A compiled task as plain data: expression terms, statements, the objects they name with the
geometry needed to evaluate them from poses alone, and their JSON form (scene JSON key "task")."""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

FORMAT = "prsc-task"
VERSION = 1
DEFAULT_HOLD = 0.5  # s: `goal EXPR` without `for` holds this long (docs/tasks.md)
TASK_FILE = "task.json"  # a URDF bundle's task file
TASK_SUFFIX = ".task.json"
"""Scene k's task file beside its MJCF, SDF or USD file: `<target>/<k>.task.json` (a URDF bundle holds
it as `task.json`, the scene JSON under "task"). One per scene: the task holds each object's box."""

PREDICATES = frozenset({"and", "or", "not", "compare", "in", "on", "left", "right", "ahead", "behind", "above",
                        "below", "touches", "holds", "at_rest", "upright", "visible", "true"})
"""Term ops whose value is true or false (with a robustness); the others are numbers or vectors."""
DIRECTIONS = {"left": (-1.0, 0.0, 0.0), "right": (1.0, 0.0, 0.0), "ahead": (0.0, 1.0, 0.0),
              "behind": (0.0, -1.0, 0.0), "above": (0.0, 0.0, 1.0), "below": (0.0, 0.0, -1.0)}
"""Each direction relation's side as an axis of the target's frame (docs/language.md, Specifiers)."""


@dataclass(frozen=True)
class Term:
    """One node of a task expression.

    op: const (value), vector (args x, y, z), object (name), link (name: the link; args: its object,
    `X.links["NAME"]`), attr (name: position x y z speed width
    length height; args: the target), arith (name: + - * /), neg, distance (2 args), compare (name:
    < <= > >= == !=), and, or, not, a relation (in on left right ahead behind above below touches
    holds at_rest upright visible; args subject[, target[, by]]; completely)."""

    op: str
    args: tuple[Term, ...] = ()
    value: float | None = None
    name: str | None = None
    completely: bool = False

    @property
    def is_predicate(self) -> bool:
        """Whether the term is true or false (else a number or a vector)."""
        return self.op in PREDICATES

    def to_json(self) -> dict[str, Any]:
        """The term as JSON data."""
        out: dict[str, Any] = {"op": self.op}
        if self.args:
            out["args"] = [a.to_json() for a in self.args]
        if self.value is not None:
            out["value"] = self.value
        if self.name is not None:
            out["name"] = self.name
        if self.completely:
            out["completely"] = True
        return out

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> Term:
        """The term of its JSON data."""
        return cls(str(data["op"]), tuple(cls.from_json(a) for a in data.get("args", ())),
                   None if data.get("value") is None else float(data["value"]), data.get("name"),
                   bool(data.get("completely", False)))

    @property
    def key(self) -> str | None:
        """The name an object or a link goes by in a world state's poses and distances: the object's
        name, or `object/link` (as a robot's finger links are named)."""
        if self.op == "link":
            return link_key(str(self.args[0].name), str(self.name))
        return self.name if self.op == "object" else None

    def objects(self) -> set[str]:
        """Names of the objects the term reads."""
        out = {self.name} if self.op == "object" and self.name is not None else set()
        for a in self.args:
            out |= a.objects()
        return out


@dataclass(frozen=True)
class Goal:
    """`goal EXPR for T seconds`."""

    expr: Term
    hold: float = DEFAULT_HOLD
    line: int = 0


@dataclass(frozen=True)
class Failure:
    """`fail "LABEL" when EXPR`."""

    label: str
    expr: Term
    line: int = 0


@dataclass(frozen=True)
class Record:
    """`record [initial|final] EXPR as NAME` (when: initial, final or step)."""

    name: str
    when: str
    expr: Term
    line: int = 0


def link_key(obj: str, link: str) -> str:
    """The name link `link` of object `obj` goes by in poses and distances (`cab/drawer`)."""
    return f"{obj}/{link}"


@dataclass(frozen=True)
class TaskStatements:
    """The task statements of a spec, the same in every scene (with the links they name, read from
    their objects' files: a link's geometry does not change from scene to scene)."""

    goals: tuple[Goal, ...] = ()
    failures: tuple[Failure, ...] = ()
    time_limit: float | None = None
    records: tuple[Record, ...] = ()
    links: tuple[TaskObject, ...] = ()

    def __bool__(self) -> bool:
        return bool(self.goals or self.failures or self.records or self.time_limit is not None)

    def objects(self) -> set[str]:
        """Names of every object the statements read."""
        out: set[str] = set()
        for statement in (*self.goals, *self.failures, *self.records):
            out |= statement.expr.objects()
        return out


@dataclass(frozen=True)
class Region:
    """A convex prism in an object's box frame: footprint rows n . (x, y) <= c (unit n), z in [low, high]."""

    normals: tuple[tuple[float, float], ...]
    offsets: tuple[float, ...]
    low: float
    high: float


@dataclass(frozen=True)
class LinkFrame:
    """Where a link's box sits: link (body) `link` of object `of`, its box centre `offset` in the
    link's own frame (the frame MuJoCo's body and pybullet's link state give), its axes the link's."""

    of: str
    link: str
    offset: tuple[float, float, float]


@dataclass(frozen=True)
class TaskObject:
    """What the evaluator knows of one object besides its pose: its box, the surface `on` means (a
    container's floor inside its walls, else the box's top face; `in` a container means `on` it, as
    in the sampler), the camera's field of view and a robot's finger links (`holds`)."""

    name: str
    dimensions: tuple[float, float, float]
    support: Region  # `on`: the footprint and the surface's height (low == high), in the box frame
    container: bool = False
    camera: tuple[float, float] | None = None  # (vertical field of view in degrees, width / height)
    fingers: tuple[str, ...] = ()  # names of the finger links in the robot's own file ("leftfinger")
    static: bool = False
    # A link (`X.links["NAME"]`, named `X/NAME`): where its box is in the link frame, and its interior
    # (`in`: the floor within its walls) beside its support surface (`on`), both in its box frame.
    link: LinkFrame | None = None
    interior: Region | None = None
    # A robot (the scene names its tool frame) touches with its moving links when mounted: its base
    # rests where it was placed. Furniture touches with all its parts. None: a task file from before
    # the flag, read as then (every fixed articulated object by its moving links).
    robot: bool | None = False

    @property
    def touches_by_moving_links(self) -> bool:
        """Whether, fixed and articulated, it touches with its moving links only: a robot does (its base
        rests where it was placed), furniture does not; a task file without the flag, as it was read then."""
        return self.robot is not False


@dataclass(frozen=True)
class Task:
    """A compiled task: the statements and every object of the scene (`holds` asks about all of them),
    then every link the statements name (`cab/drawer`)."""

    statements: TaskStatements
    objects: tuple[TaskObject, ...] = field(default=())

    def object(self, name: str) -> TaskObject:
        """The object of this name."""
        for o in self.objects:
            if o.name == name:
                return o
        raise KeyError(name)

    def touches_by_moving_links(self, name: str) -> bool:
        """Whether object `name`, fixed and articulated, touches with its moving links only
        (TaskObject.touches_by_moving_links; an object the task does not list, as before the flag)."""
        found = next((o for o in self.objects if o.name == name), None)
        return found is None or found.touches_by_moving_links

    def labels(self) -> tuple[str, ...]:
        """The robustness keys of a record: goal, then fail:LABEL of each failure."""
        return ("goal",) + tuple(f"fail:{f.label}" for f in self.statements.failures)

    def to_json(self) -> dict[str, Any]:
        """The task as JSON data (scene JSON key "task", every output folder's task.json)."""
        s = self.statements
        return {
            "format": FORMAT, "version": VERSION,
            "goals": [{"expr": g.expr.to_json(), "hold": g.hold, "line": g.line} for g in s.goals],
            "failures": [{"label": f.label, "expr": f.expr.to_json(), "line": f.line} for f in s.failures],
            "time_limit": s.time_limit,
            "records": [{"name": r.name, "when": r.when, "expr": r.expr.to_json(), "line": r.line} for r in s.records],
            "objects": [_object_json(o) for o in self.objects],
        }

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> Task:
        """The task of its JSON data."""
        if data.get("format") != FORMAT:
            raise ValueError(f"not a compiled task (format {data.get('format')!r}, expected {FORMAT!r})")
        statements = TaskStatements(
            goals=tuple(Goal(Term.from_json(g["expr"]), float(g["hold"]), int(g.get("line", 0))) for g in data["goals"]),
            failures=tuple(Failure(str(f["label"]), Term.from_json(f["expr"]), int(f.get("line", 0)))
                           for f in data["failures"]),
            time_limit=None if data.get("time_limit") is None else float(data["time_limit"]),
            records=tuple(Record(str(r["name"]), str(r["when"]), Term.from_json(r["expr"]), int(r.get("line", 0)))
                          for r in data["records"]),
        )
        objects = tuple(_object_of(o) for o in data["objects"])
        return cls(replace(statements, links=tuple(o for o in objects if o.link is not None)), objects)

    def bodies(self) -> tuple[TaskObject, ...]:
        """The scene's objects, without the links the statements name."""
        return tuple(o for o in self.objects if o.link is None)

    def links(self) -> tuple[TaskObject, ...]:
        """The links the statements name (`cab/drawer`)."""
        return tuple(o for o in self.objects if o.link is not None)


def task_file(output: str | os.PathLike[str]) -> Path:
    """The task file of one scene's output: `<k>.task.json` beside `mjcf/<k>.xml`, `sdf/<k>.sdf` or
    `usd/<k>.usda`, and `task.json` inside a URDF bundle folder `urdf/<k>/`."""
    path = Path(output)
    if path.is_dir():
        return path / TASK_FILE
    return path.with_name(path.name.split(".", 1)[0] + TASK_SUFFIX)


def _region_json(r: Region) -> dict[str, Any]:
    return {"normals": [list(n) for n in r.normals], "offsets": list(r.offsets), "low": r.low, "high": r.high}


def _region_of(d: dict[str, Any]) -> Region:
    return Region(tuple((float(a), float(b)) for a, b in d["normals"]), tuple(float(c) for c in d["offsets"]),
                  float(d["low"]), float(d["high"]))


def _object_json(o: TaskObject) -> dict[str, Any]:
    out = {"name": o.name, "dimensions": list(o.dimensions), "container": o.container,
           "support": _region_json(o.support), "camera": None if o.camera is None else list(o.camera),
           "fingers": list(o.fingers), "static": o.static, "robot": o.robot}
    if o.link is not None:
        out["link"] = {"of": o.link.of, "name": o.link.link, "offset": list(o.link.offset)}
        out["interior"] = None if o.interior is None else _region_json(o.interior)
    return out


def _object_of(d: dict[str, Any]) -> TaskObject:
    w, l, h = (float(v) for v in d["dimensions"])
    return TaskObject(str(d["name"]), (w, l, h), _region_of(d["support"]), bool(d.get("container", False)),
                      None if d.get("camera") is None else (float(d["camera"][0]), float(d["camera"][1])),
                      tuple(str(f) for f in d.get("fingers", ())), bool(d.get("static", False)),
                      None if d.get("link") is None else LinkFrame(str(d["link"]["of"]), str(d["link"]["name"]),
                                                                   tuple(float(v) for v in d["link"]["offset"])),
                      None if d.get("interior") is None else _region_of(d["interior"]),
                      None if d.get("robot") is None else bool(d["robot"]))
