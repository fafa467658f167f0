"""A task's statements bound to one scene: each object's box, support surface, camera and fingers,
read from the scene JSON (docs/scene-json.md), so the task evaluates from poses alone."""

from __future__ import annotations

from typing import Any

from prsc.geometry.container import Interior, asset_interior, declared_interior
from prsc.task.task_regions import box_region
from prsc.task.terms import Region, Task, TaskObject, TaskStatements

FINGERS = "fingers"
"""The property naming a robot's finger links in its own file (`holds`): a library arm's are
the library's (prsc/library/<arm>.json), a spec may state a file arm's (`with fingers [...]`)."""


def _interior(obj: dict[str, Any]) -> Interior | None:
    dims = tuple(float(v) for v in obj["dimensions"])
    declared = declared_interior(dims, obj.get("properties", {}))  # type: ignore[arg-type]
    return declared if declared is not None else asset_interior(obj.get("model"), dims)  # type: ignore[arg-type]


def task_object(obj: dict[str, Any]) -> TaskObject:
    """One scene JSON object as the evaluator sees it."""
    dims = tuple(float(v) for v in obj["dimensions"])
    interior = _interior(obj)
    if interior is None:
        top = box_region(dims)  # type: ignore[arg-type]
        support = Region(top.normals, top.offsets, top.high, top.high)
    else:
        normals, offsets = interior.edges()
        support = Region(tuple((float(a), float(b)) for a, b in normals), tuple(float(c) for c in offsets),
                         interior.floor_top, interior.floor_top)
    camera = obj.get("camera")
    view = None if not camera else (float(camera["fovy"]), float(camera["resolution"][0]) / float(camera["resolution"][1]))
    return TaskObject(str(obj["name"]), dims, support, interior is not None, view,  # type: ignore[arg-type]
                      tuple(str(f) for f in obj.get("properties", {}).get(FINGERS, ())), bool(obj.get("static", False)))


def bind_task(statements: TaskStatements, scene: dict[str, Any]) -> Task:
    """The compiled task of one scene."""
    return Task(statements, tuple(task_object(o) for o in scene["objects"]))
