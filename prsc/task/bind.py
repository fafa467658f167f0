"""A task's statements bound to one scene: each object's box, support surface, camera and fingers,
read from the scene JSON (docs/scene-json.md), so the task evaluates from poses alone."""

from __future__ import annotations

from typing import Any

import numpy as np

from prsc.geometry.container import Interior, asset_interior, declared_interior
from prsc.geometry.link_surfaces import Box, Face, link_surfaces
from prsc.task.task_regions import box_region
from prsc.task.terms import LinkFrame, Region, Task, TaskObject, TaskStatements, link_key

FINGERS = "fingers"
"""The property naming a robot's finger links in its own file (`holds`): a library arm's are
the library's (prsc/library/<arm>.json), a spec may state a file arm's (`with fingers [...]`)."""


ROBOT_TOOL = "tcp"
"""The property a robot has and furniture does not: its tool frame (every Robot has one)."""


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
    properties = obj.get("properties") or {}
    return TaskObject(str(obj["name"]), dims, support, interior is not None, view,  # type: ignore[arg-type]
                      tuple(str(f) for f in properties.get(FINGERS, ())), bool(obj.get("static", False)),
                      robot=ROBOT_TOOL in properties)


def link_object(obj: str, link: str, boxes: tuple[Box, ...]) -> TaskObject:
    """Link `link` of object `obj` as the evaluator sees it (named `obj/link`): the box of its collision
    geometry (`boxes`, in the link frame), its support surface and its interior, as the sampler reads
    them (prsc/geometry/link_surfaces.py) and as they move with the link."""
    low = np.min([b[0] for b in boxes], axis=0) if boxes else np.zeros(3)
    high = np.max([b[1] for b in boxes], axis=0) if boxes else np.zeros(3)
    centre, dims = (low + high) / 2, tuple(float(v) for v in high - low)
    surfaces = link_surfaces(tuple(boxes))

    def region(face: Face | None) -> Region | None:
        if face is None:
            return None
        cx, cy, cz = centre.tolist()
        return Region(((1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)),
                      (face.x_high - cx, cx - face.x_low, face.y_high - cy, cy - face.y_low), face.z - cz, face.z - cz)

    top = box_region(dims)  # type: ignore[arg-type]
    support = region(surfaces.support) or Region(top.normals, top.offsets, top.high, top.high)
    # not a container: `in` it rests on its interior, `on` it on its support surface (robustness.rests_in)
    return TaskObject(link_key(obj, link), dims, support,  # type: ignore[arg-type]
                      link=LinkFrame(obj, link, tuple(float(v) for v in centre)),  # type: ignore[arg-type]
                      interior=region(surfaces.interior))


def bind_task(statements: TaskStatements, scene: dict[str, Any]) -> Task:
    """The compiled task of one scene: its objects, then the links the statements name."""
    return Task(statements, tuple(task_object(o) for o in scene["objects"]) + statements.links)
