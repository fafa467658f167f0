"""One handover episode: perceive, pick with the left Panda, hand over, pick with the right, place.

The controller is the paper's open-loop pipeline (section IV): the ceiling RGB-D camera
locates the cube, IK plans top-down tool waypoints, position servos track them, and the
grasp is physical (finger friction against gripper force). The outcome is decided from
simulator ground truth at the first failing stage.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

import mujoco
import numpy as np

from prsc.assets import panda
from prsc.backends.runner.motion import Arm, Simulation, Unreachable
from prsc.backends.runner.perception import CeilingCamera, locate_cube
from prsc.backends.runner.roles import Roles, find_roles, footprint_distance
from prsc.geometry.rotations import quat_to_matrix

OUTCOMES = ("success", "perception_fault", "no_path", "poor_grip", "other")

PERCEPTION_TOLERANCE = 0.02  # m: a detection further than this from the truth is a fault
APPROACH_HEIGHT = 0.12  # m above the cube centre before descending
LIFT_HEIGHT = 0.15  # m the cube is lifted
HANDOVER_REACH = 0.45  # m ahead of the robots' midpoint, along their mean forward axis
PLACE_CLEARANCE = 0.012  # m between the cube's bottom and the surface when released
SLIP_TOLERANCE = 0.02  # m the cube may shift in the gripper between lift and release
MIN_GRIP_OPENING = 0.25  # fingers closer than this fraction of the cube's half width hold nothing


@dataclass(frozen=True)
class EpisodeResult:
    """One line of results.jsonl."""

    index: int
    seed: int
    outcome: str
    reason: str
    cube_initial: list[float]
    cube_final: list[float]
    sim_seconds: float
    wall_seconds: float

    def to_json(self) -> dict:
        """The JSON object written to results.jsonl."""
        return asdict(self)


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

    def __init__(self, scene: dict, model: mujoco.MjModel, data: mujoco.MjData,
                 observer: Callable[[str, mujoco.MjModel, mujoco.MjData], None] | None = None):
        self.scene = scene
        self.roles = find_roles(scene)
        self.model = model
        self.data = data
        self.sim = Simulation(model, data, observer)
        self.cube_id = model.body(self.roles.cube["name"]).id
        dims = np.asarray(self.roles.cube["dimensions"], float)
        self.cube_half = float(dims[2]) / 2
        self.cube_half_width = float(min(dims[0], dims[1])) / 2
        self.left = Arm.from_scene(model, data, self.roles.left_robot["name"])
        self.right = Arm.from_scene(model, data, self.roles.right_robot["name"])
        self.camera: CeilingCamera | None = None

    def cube_position(self) -> np.ndarray:
        """Ground-truth cube centre."""
        return self.data.xpos[self.cube_id].copy()

    def perceive(self, stage: str) -> np.ndarray:
        """Locate the cube with the ceiling camera; a miss or a > 2 cm error ends the episode."""
        if self.camera is None:
            self.camera = CeilingCamera(self.model, self.roles.camera["name"])
        rgb, depth = self.camera.capture(self.data)
        cam_pos, cam_mat = self.camera.pose(self.data)
        detection = locate_cube(rgb, depth, self.camera.intrinsics, cam_pos, cam_mat,
                                self.roles.cube["color"], self.cube_half)
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

    def grip_offset(self, arm: Arm) -> np.ndarray:
        """Cube centre relative to the tool centre (ground truth)."""
        return self.cube_position() - self.data.site_xpos[arm.tcp_id]

    def gripper_closed_empty(self, arm: Arm) -> bool:
        """Whether the fingers closed (nearly) fully, i.e. on nothing."""
        return bool(self.data.qpos[arm.finger_adr] < MIN_GRIP_OPENING * self.cube_half_width)

    def pick_and_place(self, arm: Arm, cube: np.ndarray, place: np.ndarray, stage: str, go_home: bool) -> None:
        """Plan every waypoint, then pick the cube at `cube` and release it with its centre at `place`."""
        up = np.array([0.0, 0.0, 1.0])
        home = np.array(panda.HOME_QPOS)
        above = cube + up * APPROACH_HEIGHT
        lifted = cube + up * LIFT_HEIGHT
        over_place = place + up * max(LIFT_HEIGHT, APPROACH_HEIGHT)
        try:
            q_above = arm.plan_point(above, home, f"the point above the cube ({stage})")
            descend = arm.plan_line(above, cube, q_above, f"the cube ({stage})")
            lift = arm.plan_line(cube, lifted, descend[-1], f"the lift above the cube ({stage})")
            q_over = arm.plan_point(over_place, lift[-1], f"the point above the release ({stage})")
            lower = arm.plan_line(over_place, place, q_over, f"the release point ({stage})")
            retreat = arm.plan_line(place, over_place, lower[-1], f"the retreat ({stage})")
        except Unreachable as error:
            raise EpisodeEnd("no_path", str(error)) from None

        start_z = self.cube_position()[2]
        self.sim.move(arm, [q_above])
        self.sim.snapshot(f"above the cube ({stage})")
        self.sim.move(arm, descend, seconds=0.8)
        self.sim.snapshot(f"grasp ({stage})")
        self.sim.grip(arm, panda.GRIPPER_CLOSED, 0.5)
        if self.gripper_closed_empty(arm):
            raise EpisodeEnd("poor_grip", f"{stage}: the gripper closed on nothing")
        self.sim.move(arm, lift, seconds=0.8)
        self.sim.wait(0.2)
        self.sim.snapshot(f"lift ({stage})")
        rise = self.cube_position()[2] - start_z
        if rise < 0.5 * LIFT_HEIGHT:
            raise EpisodeEnd("poor_grip", f"{stage}: grasp closed but the cube was not lifted "
                                          f"(it rose {rise * 100:.1f} cm of {LIFT_HEIGHT * 100:.0f})")
        held = self.grip_offset(arm)
        self.sim.move(arm, [q_over])
        self.sim.move(arm, lower, seconds=0.8)
        self.sim.snapshot(f"release ({stage})")
        slip = float(np.linalg.norm(self.grip_offset(arm) - held))
        if slip > SLIP_TOLERANCE:
            raise EpisodeEnd("poor_grip", f"{stage}: the cube slipped {slip * 100:.1f} cm in the gripper while carried")
        self.sim.grip(arm, panda.GRIPPER_OPEN, 0.4)
        self.sim.move(arm, retreat, seconds=0.6)
        if go_home:
            self.sim.move(arm, [home])

    def run(self) -> tuple[str, str]:
        """Run the task; return (outcome, reason)."""
        roles = self.roles
        try:
            handover = _handover_point(self.scene, roles, self.cube_half)
            target = np.asarray(roles.target_tray["position"], float).copy()
            tray_bottom = target[2] - float(np.abs(quat_to_matrix(roles.target_tray["quaternion"])[2])
                                             @ (np.asarray(roles.target_tray["dimensions"], float) / 2))
            target[2] = tray_bottom + self.cube_half + PLACE_CLEARANCE
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
        tray = self.model.body(self.roles.target_tray["name"]).id
        rot = self.data.xmat[tray].reshape(3, 3)
        local = rot.T @ (self.cube_position() - self.data.xpos[tray])
        half = np.asarray(self.roles.target_tray["dimensions"], float) / 2
        velocity = np.zeros(6)
        mujoco.mj_objectVelocity(self.model, self.data, mujoco.mjtObj.mjOBJ_BODY, self.cube_id, velocity, 0)
        speed = float(np.linalg.norm(velocity[3:]))
        inside = bool(np.all(np.abs(local[:2]) < half[:2]) and -half[2] < local[2] < half[2] + 2 * self.cube_half)
        if inside and speed < 0.05:
            return "success", ""
        where = np.round(self.cube_position(), 3).tolist()
        if inside:
            return "other", f"cube inside the target tray but still moving ({speed:.2f} m/s)"
        return "other", f"cube ended outside the target tray, at {where}"


def load_model(mjcf_path: str | Path) -> mujoco.MjModel:
    """Load a scene MJCF with the simulation options it was compiled with (prsc.assets.simulation)."""
    return mujoco.MjModel.from_xml_path(str(mjcf_path))


def run_episode(scene: dict, mjcf_path: str | Path, seed: int | None = None,
                observer: Callable[[str, mujoco.MjModel, mujoco.MjData], None] | None = None) -> EpisodeResult:
    """Simulate the handover controller in one compiled scene and classify the outcome.

    The controller draws nothing at random: every failure comes from the scene itself.
    `seed` is recorded (default: the scene's own seed); `observer(label, model, data)` is called at
    the controller's key moments (frame recording).
    """
    started = time.perf_counter()
    model = load_model(mjcf_path)
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    episode = HandoverEpisode(scene, model, data, observer)
    for arm in (episode.left, episode.right):
        arm.reset_home(model, data)
    mujoco.mj_forward(model, data)
    episode.sim.wait(0.3)  # the cube and trays settle onto their supports
    cube_initial = episode.cube_position()
    try:
        outcome, reason = episode.run()
    except (FloatingPointError, mujoco.FatalError) as error:
        outcome, reason = "other", f"simulation failed: {error}"
    finally:
        if episode.camera is not None:
            episode.camera.close()
    return EpisodeResult(
        index=int(scene.get("index", 0)),
        seed=int(scene.get("seed", 0) if seed is None else seed),
        outcome=outcome,
        reason=reason,
        cube_initial=[round(float(v), 5) for v in cube_initial],
        cube_final=[round(float(v), 5) for v in episode.cube_position()],
        sim_seconds=round(float(data.time), 3),
        wall_seconds=round(time.perf_counter() - started, 3),
    )
