"""The handover controller: perceive, pick with the left arm, hand over, pick with the right, place.

The controller is the paper's open-loop pipeline (section IV): the ceiling RGB-D camera
locates the cube, IK plans top-down tool waypoints, position servos track them, and the
grasp is physical (finger friction against gripper force). The outcome is decided from
simulator ground truth at the first failing stage. It drives any two arms with grippers,
through the interface the example `pick` uses (prsc/runner/motion.py). `handover` is the
default controller of `prsc run` (see controller.py for the interface every controller
follows).
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from prsc.runner.grasping import PLACE_CLEARANCE, GraspFailure, HeldCube
from prsc.runner.motion import Arm, Simulation, Unreachable
from prsc.runner.perception import CeilingCamera, locate_cube
from prsc.runner.report import plot_cube_map
from prsc.runner.roles import Roles, find_roles, footprint_distance
from prsc.geometry.rotations import quat_to_matrix

OUTCOMES = ("success", "perception_fault", "no_path", "poor_grip", "other")

PERCEPTION_TOLERANCE = 0.02  # m: a detection further than this from the truth is a fault
HANDOVER_REACH = 0.45  # m ahead of the robots' midpoint, along their mean forward axis


class EpisodeEnd(Exception):
    """Stops an episode with an outcome."""

    def __init__(self, outcome: str, reason: str):
        super().__init__(reason)
        self.outcome = outcome
        self.reason = reason


def _support_height(scene: dict, roles: Roles, point: np.ndarray) -> float | None:
    """Top height of the highest object (not a robot, camera or the cube) under a point."""
    skip = {roles.left_robot["name"], roles.right_robot["name"], roles.camera["name"], roles.cube["name"]}
    tops = []
    for obj in scene["objects"]:
        if obj["name"] in skip or obj.get("camera") is not None:
            continue
        if footprint_distance(obj, point) == 0.0:
            rot = quat_to_matrix(obj["quaternion"])
            half = np.asarray(obj["dimensions"], float) / 2
            tops.append(obj["position"][2] + float(np.abs(rot[2]) @ half))
    return max(tops) if tops else None


def _handover_point(scene: dict, roles: Roles, cube_half: float) -> np.ndarray:
    """Where the left arm puts the cube down for the right arm: between them, ahead of both."""
    left, right = (np.asarray(r["position"], float) for r in (roles.left_robot, roles.right_robot))
    forward = sum(quat_to_matrix(r["quaternion"])[:, 1] for r in (roles.left_robot, roles.right_robot))
    forward[2] = 0.0
    forward /= np.linalg.norm(forward)
    point = (left + right) / 2 + HANDOVER_REACH * forward
    surface = _support_height(scene, roles, point)
    if surface is None:
        raise EpisodeEnd("other", "no surface to put the cube on at the handover point")
    point[2] = surface + cube_half + PLACE_CLEARANCE
    return point


class HandoverEpisode:
    """The controller and its ground-truth checks for one compiled scene."""

    def __init__(self, scene: dict, model: mujoco.MjModel, data: mujoco.MjData):
        self.scene = scene
        self.roles = find_roles(scene)
        self.sim = Simulation(model, data)
        self.cube = HeldCube(self.sim, self.roles.cube)
        self.left = Arm.of(self.roles.left_robot, model, data)
        self.right = Arm.of(self.roles.right_robot, model, data)
        for arm in (self.left, self.right):  # a file arm's ready pose may leave its fingers shut
            self.sim.command_gripper(arm, closed=False)
        self.camera: CeilingCamera | None = None

    def cube_position(self) -> np.ndarray:
        """Ground-truth cube centre."""
        return self.cube.position()

    def perceive(self, stage: str) -> np.ndarray:
        """Locate the cube with the ceiling camera; a miss or a > 2 cm error ends the episode."""
        if self.camera is None:
            self.camera = CeilingCamera(self.sim.model, self.roles.camera["body"])
        rgb, depth = self.camera.capture(self.sim.data)
        cam_pos, cam_mat = self.camera.pose(self.sim.data)
        detection = locate_cube(rgb, depth, self.camera.intrinsics, cam_pos, cam_mat,
                                self.roles.cube["color"], self.cube.half_height)
        self.sim.snapshot(f"perceive ({stage})")
        if detection is None:
            raise EpisodeEnd("perception_fault", f"{stage}: cube not detected in the camera image")
        error = float(np.linalg.norm(detection.centre - self.cube_position()))
        if error > PERCEPTION_TOLERANCE:
            why = "cut by the image border" if detection.touches_border else "partly hidden or misread"
            raise EpisodeEnd("perception_fault",
                             f"{stage}: cube located {error * 100:.1f} cm from its true position ({why}, "
                             f"{detection.pixels} px)")
        return detection.centre

    def pick_and_place(self, arm: Arm, cube: np.ndarray, place: np.ndarray, stage: str, go_home: bool) -> None:
        """Move the cube from `cube` to `place` with one arm; an unreachable waypoint is `no_path`,
        a failed grasp `poor_grip`."""
        try:
            self.cube.pick_and_place(arm, cube, place, stage, go_home)
        except Unreachable as error:
            raise EpisodeEnd("no_path", str(error)) from None
        except GraspFailure as failure:
            raise EpisodeEnd("poor_grip", str(failure)) from None

    def run(self) -> tuple[str, str]:
        """Run the task; return (outcome, reason)."""
        roles = self.roles
        try:
            handover = _handover_point(self.scene, roles, self.cube.half_height)
            target = self.cube.release_point(roles.target_tray)
            cube = self.perceive("source tray")
            # The left arm goes home afterwards to clear the camera's view of the handover point.
            self.pick_and_place(self.left, cube, handover, "left arm", go_home=True)
            self.sim.wait(0.3)
            cube = self.perceive("handover")
            self.pick_and_place(self.right, cube, target, "right arm", go_home=False)
            self.sim.wait(0.5)
        except EpisodeEnd as end:
            self.sim.snapshot(f"stop: {end.outcome}")
            return end.outcome, end.reason
        self.sim.snapshot("end")
        return self.final_outcome()

    def final_outcome(self) -> tuple[str, str]:
        """`success` when the cube rests inside the target tray, else `other` with where it is."""
        inside, speed = self.cube.resting_in(self.roles.target_tray)
        if inside and speed < 0.05:
            return "success", ""
        where = np.round(self.cube_position(), 3).tolist()
        if inside:
            return "other", f"cube inside the target tray but still moving ({speed:.2f} m/s)"
        return "other", f"cube ended outside the target tray, at {where}"


class HandoverController:
    """`prsc run`'s default controller: the two-arm handover of the paper's case study.

    The controller draws nothing at random: every failure comes from the scene itself."""

    outcomes = OUTCOMES

    def __call__(self, scene: dict, model: mujoco.MjModel, data: mujoco.MjData) -> dict:
        """Run one episode; the outcome, its reason and where the cube started and ended."""
        episode = HandoverEpisode(scene, model, data)
        episode.sim.wait(0.3)  # the cube and trays settle onto their supports
        cube_initial = episode.cube_position()
        try:
            outcome, reason = episode.run()
        except (FloatingPointError, mujoco.FatalError) as error:
            outcome, reason = "other", f"simulation failed: {error}"
        finally:
            if episode.camera is not None:
                episode.camera.close()
        return {"outcome": outcome, "reason": reason,
                "cube_initial": [round(float(v), 5) for v in cube_initial],
                "cube_final": [round(float(v), 5) for v in episode.cube_position()]}

    @staticmethod
    def check(scene: dict) -> None:
        """Refuse a scene without two arms, two Trays, one Cube and one Camera (PrscError)."""
        find_roles(scene)

    @staticmethod
    def report(records: list[dict], scenes: list[dict], folder: Path, title: str) -> list[Path]:
        """The cube's start positions coloured by outcome (cube_map.png)."""
        trays = [find_roles(scene).source_tray for scene in scenes]
        return [plot_cube_map(records, trays, folder / "cube_map.png", title)]


handover = HandoverController()
