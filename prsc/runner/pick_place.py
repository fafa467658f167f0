"""An example controller for users: one arm with a gripper moves a cube from one tray to the other.

    prsc run specs/pick_place.prs --controller prsc.runner.pick_place:pick_place -n 20

It knows where the cube is (simulator ground truth, no camera), plans top-down IK
waypoints and carries the cube with a physical grasp. Its outcomes: `placed`,
`unreachable` (IK misses a waypoint), `dropped` (the grasp failed) and `missed` (the cube
ended outside the target tray). Copy it as a starting point for a controller of your own.
"""

from __future__ import annotations

import mujoco
import numpy as np

from prsc.runner.grasping import GraspFailure, HeldCube
from prsc.runner.motion import Arm, Simulation, Unreachable
from prsc.runner.roles import footprint_distance, objects_by_class, require_arm
from prsc.errors import PrscError


def _roles(scene: dict) -> tuple[dict, dict, dict, dict]:
    """(robot, cube, source tray, target tray): the tray under the cube is the source."""
    found = objects_by_class(scene, ("Robot", "Tray", "Cube"))
    if len(found["Robot"]) != 1 or len(found["Tray"]) != 2 or len(found["Cube"]) != 1:
        counts = ", ".join(f"{len(v)} {k}" for k, v in found.items())
        raise PrscError(f"scene {scene.get('spec', '?')} #{scene.get('index', '?')} does not fit pick_place: "
                        f"it needs one Robot, two Trays and one Cube (found {counts})")
    robot, cube = found["Robot"][0], found["Cube"][0]
    require_arm(robot, "pick_place drives an arm with a gripper")
    source, target = sorted(found["Tray"], key=lambda t: (footprint_distance(t, cube["position"]), t["name"]))
    return robot, cube, source, target


class PickPlace:
    """Pick the cube from its tray, place it in the other one."""

    outcomes = ("placed", "unreachable", "dropped", "missed")

    def __call__(self, scene: dict, model: mujoco.MjModel, data: mujoco.MjData) -> dict:
        """One episode: the outcome, why, and how far the cube ended from the target tray's centre."""
        robot, cube_obj, _, target = _roles(scene)
        sim = Simulation(model, data)
        arm = Arm.of(robot, model, data)
        sim.command_gripper(arm, closed=False)
        cube = HeldCube(sim, cube_obj)
        sim.wait(0.3)  # the objects settle onto their supports
        place = cube.release_point(target)
        try:
            cube.pick_and_place(arm, cube.position(), place, "pick and place", go_home=True)
            sim.wait(0.5)
            inside, speed = cube.resting_in(target)
            outcome, reason = ("placed", "") if inside and speed < 0.05 else (
                "missed", f"the cube ended at {np.round(cube.position(), 3).tolist()}, moving {speed:.2f} m/s")
        except Unreachable as error:
            outcome, reason = "unreachable", str(error)
        except GraspFailure as failure:
            outcome, reason = "dropped", str(failure)
        miss = float(np.linalg.norm((cube.position() - place)[:2]))
        return {"outcome": outcome, "reason": reason, "distance_to_target": round(miss, 4)}

    @staticmethod
    def check(scene: dict) -> None:
        """Refuse a scene without one arm, two Trays and one Cube."""
        _roles(scene)


pick_place = PickPlace()
