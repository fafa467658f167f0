"""Whether a compiled scene is at rest: each MJCF stepped in MuJoCo, every free object's drift.

`prsc compile --settle-check` runs it on the scenes it wrote: each scene's MJCF is simulated
for 1 s with the robots held at their `home` keyframe, and the largest displacement of any
free object is reported. An object that moves more than 2 mm is listed with the likely
cause, read off the scene JSON: what it was placed on and how each backend builds that
(a hollow container's rim, a declared interior whose model is unknown and so simulated as
a solid box, a footprint over an edge or across a wall).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable

import mujoco
import numpy as np

from prsc.user_assets.asset_files import names_asset_file
from prsc.assets.registry import is_hollow, is_robot, part_recipe
from prsc.backends.scene import Scene, SceneObject, parse_scene
from prsc.runner.settle_report import settle
from prsc.geometry.container import Interior, declared_interior
from prsc.geometry.rotations import quat_to_matrix

SECONDS = 1.0
LIMIT = 0.002  # m: a free object moving more than this is not at rest
CONTACT = 1e-4  # m: how close a bottom must be to a surface to rest on it


@dataclass(frozen=True)
class Drift:
    """One free object that moved more than the limit, and why it probably did."""

    name: str
    distance: float  # metres
    cause: str


@dataclass(frozen=True)
class SceneRest:
    """The settle check of one scene: the largest displacement of any free object."""

    index: int
    largest: float  # metres (0 with no free object)
    drifts: tuple[Drift, ...]  # the objects over the limit, largest first
    trivial: bool | None = None  # the task's goal holds at the start (None: the spec states no goal)


def _frame(obj: SceneObject) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return np.asarray(obj.position, dtype=float), quat_to_matrix(obj.quaternion), 0.5 * np.asarray(obj.dimensions, dtype=float)


def _corners(obj: SceneObject) -> np.ndarray:
    """The 8 corners of the object's box in world coordinates."""
    p, r, half = _frame(obj)
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
    return p + (signs * half) @ r.T


def _bottom(obj: SceneObject) -> float:
    return float(_corners(obj)[:, 2].min())


def _interior(obj: SceneObject) -> Interior | None:
    try:
        return declared_interior(obj.dimensions, obj.properties)
    except ValueError:
        return None


def _inside(points: np.ndarray, support: SceneObject, interior: Interior | None) -> bool:
    """Whether world points project inside the support's top rectangle (or its interior)."""
    p, r, half = _frame(support)
    local = (points - p) @ r
    if interior is not None:
        normals, offsets = interior.edges()
        return bool(np.all(local[:, :2] @ normals.T <= offsets + 1e-6))
    return bool(np.all(np.abs(local[:, :2]) <= half[:2] + 1e-6))


def _known(model: str | None) -> bool:
    return model is None or part_recipe(model) is not None or is_robot(model) is not None or names_asset_file(model)


def cause(scene: Scene, obj: SceneObject) -> str:
    """The likely reason a free object moved, from what it was placed on."""
    own = [] if _known(obj.model) else [
        f"its model {obj.model!r} is unknown, simulated as a solid box, and what was placed on its declared floor "
        "pushes against it" if _interior(obj) is not None else f"its model {obj.model!r} is unknown, simulated as a plain {obj.shape}"
    ]
    bottom, corners = _bottom(obj), _corners(obj)
    centre = np.asarray(obj.position, dtype=float)[None, :]
    for support in scene.objects:
        if support is obj or not _inside(centre, support, None):
            continue
        name, top = support.label or support.name, float(_corners(support)[:, 2].max())
        interior = _interior(support)
        if interior is not None and abs(bottom - (support.position[2] + interior.floor_top)) <= CONTACT:
            if not _known(support.model):
                return "; ".join(own + [f"placed on the declared floor of {name}, whose model {support.model!r} is unknown: "
                                        f"simulated as a solid box, it pushes the object out"])
            if not _inside(corners, support, interior):
                return "; ".join(own + [f"placed with bare `on` across a wall of {name}: it tips"])
        elif abs(bottom - top) <= CONTACT:
            if is_hollow(support.model) or interior is not None:
                return "; ".join(own + [f"placed on the rim of {name} (`on (top {name})` or no declared interior), "
                                        f"but {name} is hollow: it falls in"])
            if not _inside(corners, support, None):
                return "; ".join(own + [f"placed with bare `on` over an edge of {name}: it tips"])
    return "; ".join(own or ["pushed in simulation (a neighbour, a robot, or resting on nothing)"])


def settle_scene(raw: dict, mjcf: Path, index: int = 0, seconds: float = SECONDS, limit: float = LIMIT) -> SceneRest:
    """Simulate one compiled scene and measure every free object's displacement."""
    scene = parse_scene(raw)
    model, before, after = settle(mjcf, seconds)
    largest, drifts = 0.0, []
    for obj in scene.objects:
        body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, obj.name)
        if body < 0 or model.body_jntnum[body] == 0 or model.jnt_type[model.body_jntadr[body]] != mujoco.mjtJoint.mjJNT_FREE:
            continue
        moved = float(np.linalg.norm(after[body] - before[body]))
        largest = max(largest, moved)
        if moved > limit:
            drifts.append(Drift(obj.label or obj.name, moved, cause(scene, obj)))
    drifts.sort(key=lambda d: -d.distance)
    return SceneRest(index, largest, tuple(drifts), _trivial(raw, model))


def _trivial(raw: dict, model: mujoco.MjModel) -> bool | None:
    """Whether the task's goal already holds in the scene as compiled (an episode would be `trivial`)."""
    if not (raw.get("task") or {}).get("goals"):
        return None
    from prsc.runner.harness import fresh_data
    from prsc.runner.task_monitor import TaskMonitor

    monitor = TaskMonitor(raw, model)
    monitor.update(model, fresh_data(model))
    return monitor.monitor.trivial


def settle_scenes(scenes: Iterable[tuple[int, Path, Path]], limit: float = LIMIT) -> list[SceneRest]:
    """The settle check of compiled scenes, each given as (index, scene JSON file, MJCF file)."""
    return [settle_scene(json.loads(js.read_text()), xml, index, limit=limit) for index, js, xml in scenes]


def report_lines(results: list[SceneRest], limit: float = LIMIT) -> list[str]:
    """Human-readable lines: per scene its largest displacement, the scenes over the limit with causes."""
    lines = []
    for rest in results:
        mark = "MOVES" if rest.drifts else "at rest"
        lines.append(f"scene {rest.index:05d}: largest displacement {rest.largest * 1000:.2f} mm ({mark})"
                     + ("; the task's goal already holds at the start (trivial)" if rest.trivial else ""))
        for drift in rest.drifts:
            lines.append(f"  {drift.name} moved {drift.distance * 1000:.1f} mm: {drift.cause}")
    bad = sum(1 for r in results if r.drifts)
    lines.append(f"settle check: {len(results) - bad} of {len(results)} scenes at rest "
                 f"(no free object moved more than {limit * 1000:g} mm in {SECONDS:g} s)")
    judged = [r for r in results if r.trivial is not None]
    if judged:
        lines.append(f"task: the goal already holds at the start of {sum(r.trivial for r in judged)} of {len(judged)} "
                     "scenes (trivial episodes)")
    return lines
