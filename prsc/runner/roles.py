"""Task roles of a handover scene, found from object classes (never from variable names)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from prsc.assets.articulated import robot_model
from prsc.errors import PrscError
from prsc.geometry.rotations import quat_to_matrix


@dataclass(frozen=True)
class Roles:
    """The scene objects the handover controller works with (scene JSON object dicts)."""

    left_robot: dict
    right_robot: dict
    source_tray: dict
    target_tray: dict
    cube: dict
    camera: dict


def footprint_distance(box: dict, point) -> float:
    """Horizontal distance (m) from a point to a box object's footprint; 0 inside it."""
    local = quat_to_matrix(box["quaternion"]).T @ (np.asarray(point, float) - np.asarray(box["position"], float))
    half = np.asarray(box["dimensions"], float)[:2] / 2
    outside = np.maximum(np.abs(local[:2]) - half, 0.0)
    return float(np.linalg.norm(outside))


def objects_by_class(scene: dict, wanted: tuple[str, ...]) -> dict[str, list[dict]]:
    """The scene's objects of each wanted class: an object counts for the first class of its
    lineage (its class, then its ancestors in the scene's `classes` map) that is wanted."""
    ancestry = scene.get("classes") or {}
    found: dict[str, list[dict]] = {cls: [] for cls in wanted}
    for obj in scene.get("objects", []):
        lineage = [obj.get("class"), *ancestry.get(obj.get("class"), [])]
        role = next((cls for cls in lineage if cls in wanted), None)
        if role is not None:
            found[role].append(obj)
    return found


def require_arm(robot: dict, needs: str) -> None:
    """Refuse a Robot whose model is no arm (PrscError saying what the controller `needs`)."""
    if robot_model(robot.get("model")) is None:
        raise PrscError(f"Robot {robot['name']!r} has model {robot.get('model')!r}, which is no arm: {needs} "
                        "(the built-in arm, or a URDF or MJCF arm)")


def find_roles(scene: dict) -> Roles:
    """Pick the two Robots (left/right by x), source/target Tray, the Cube and the Camera.

    Each Robot must be an arm (the built-in arm, or a URDF or MJCF arm); whether it has a
    gripper is seen in the compiled model (prsc/runner/motion.py's `Arm.of`).

    An object fills a role when its class or one of its ancestors (the scene's `classes`
    map, e.g. `RedCube(Cube)`) is the role's class.
    """
    wanted = {"Robot": 2, "Tray": 2, "Cube": 1, "Camera": 1}
    by_class = objects_by_class(scene, tuple(wanted))
    problems = []
    for cls, count in wanted.items():
        found = len(by_class.get(cls, []))
        if found < count:
            problems.append(f"{count} {cls}{'s' if count > 1 else ''} (found {found})")
        elif cls in ("Cube", "Camera") and found > count:
            problems.append(f"exactly one {cls} (found {found})")
        elif found > count:
            problems.append(f"exactly {count} {cls}s (found {found})")
    if problems:
        raise PrscError(
            f"scene {scene.get('spec', '?')} #{scene.get('index', '?')} does not fit the handover task: "
            f"it needs {', '.join(problems)}; the runner expects two Robots, two Trays, one Cube and one Camera"
        )
    robots = sorted(by_class["Robot"], key=lambda o: o["position"][0])
    for robot in robots:
        require_arm(robot, "the handover drives two arms with grippers")
    cube = by_class["Cube"][0]
    trays = sorted(by_class["Tray"], key=lambda t: (footprint_distance(t, cube["position"]), t["name"]))
    return Roles(
        left_robot=robots[0], right_robot=robots[1],
        source_tray=trays[0], target_tray=trays[1],
        cube=cube, camera=by_class["Camera"][0],
    )
