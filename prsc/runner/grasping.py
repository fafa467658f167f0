"""Top-down pick and place of a box-shaped object with one arm, judged from simulator ground truth."""

from __future__ import annotations

import mujoco
import numpy as np

from prsc.runner.motion import Arm, Simulation
from prsc.geometry.rotations import quat_to_matrix
from prsc.user_assets.arm_ik import REACH_APPROACH

# m above the cube centre before descending: the approach `reachable by` certifies for every arm.
APPROACH_HEIGHT = REACH_APPROACH
LIFT_HEIGHT = 0.15  # m the cube is lifted
PLACE_CLEARANCE = 0.012  # m between the cube's bottom and the surface when released
SLIP_TOLERANCE = 0.02  # m the cube may shift in the gripper between lift and release
MIN_GRIP_OPENING = 0.5  # fingers closer to closed than this fraction of the cube's half width hold nothing


class GraspFailure(Exception):
    """The gripper closed on nothing, did not lift the cube, or lost it while carrying."""


class HeldCube:
    """A scene's cube (a free box) and the arm motions that carry it."""

    def __init__(self, sim: Simulation, cube: dict):
        self.sim = sim
        self.body = sim.model.body(cube["body"]).id
        dims = np.asarray(cube["dimensions"], float)
        self.half_height = float(dims[2]) / 2
        self.half_width = float(min(dims[0], dims[1])) / 2

    def position(self) -> np.ndarray:
        """Ground-truth cube centre."""
        return self.sim.data.xpos[self.body].copy()

    def offset_from(self, arm: Arm) -> np.ndarray:
        """Cube centre relative to the arm's tool centre."""
        return self.position() - arm.frames.tool_pose(self.sim.data)[0]

    def gripper_closed_empty(self, arm: Arm) -> bool:
        """Whether the fingers closed (nearly) fully, i.e. on nothing."""
        return arm.gripper.opening(self.sim.data, arm.frames) < MIN_GRIP_OPENING * self.half_width

    def pick_and_place(self, arm: Arm, cube: np.ndarray, place: np.ndarray, stage: str, go_home: bool) -> None:
        """Plan every waypoint, then pick the cube at `cube` and release it with its centre at `place`.

        Raises motion.Unreachable before moving when IK misses a waypoint, GraspFailure when the grasp fails."""
        sim = self.sim
        up = np.array([0.0, 0.0, 1.0])
        above = cube + up * APPROACH_HEIGHT
        lifted = cube + up * LIFT_HEIGHT
        over_place = place + up * max(LIFT_HEIGHT, APPROACH_HEIGHT)

        def plan_on(q_above: np.ndarray) -> tuple[list[np.ndarray], ...]:
            descend = arm.plan_line(above, cube, q_above, f"the cube ({stage})")
            lift = arm.plan_line(cube, lifted, descend[-1], f"the lift above the cube ({stage})")
            q_over = arm.plan_point(over_place, lift[-1], f"the point above the release ({stage})")
            lower = arm.plan_line(over_place, place, q_over, f"the release point ({stage})")
            return descend, lift, [q_over], lower, arm.plan_line(place, over_place, lower[-1], f"the retreat ({stage})")

        q_above, (descend, lift, (q_over,), lower, retreat) = arm.plan_from_home(
            above, f"the point above the cube ({stage})", plan_on)

        start_z = self.position()[2]
        sim.move(arm, [q_above])
        sim.snapshot(f"above the cube ({stage})")
        sim.move(arm, descend, seconds=0.8)
        sim.snapshot(f"grasp ({stage})")
        sim.grip(arm, True, 0.5)
        if self.gripper_closed_empty(arm):
            raise GraspFailure(f"{stage}: the gripper closed on nothing")
        sim.move(arm, lift, seconds=0.8)
        sim.wait(0.2)
        sim.snapshot(f"lift ({stage})")
        rise = self.position()[2] - start_z
        if rise < 0.5 * LIFT_HEIGHT:
            raise GraspFailure(f"{stage}: grasp closed but the cube was not lifted "
                               f"(it rose {rise * 100:.1f} cm of {LIFT_HEIGHT * 100:.0f})")
        held = self.offset_from(arm)
        sim.move(arm, [q_over])
        sim.move(arm, lower, seconds=0.8)
        sim.snapshot(f"release ({stage})")
        slip = float(np.linalg.norm(self.offset_from(arm) - held))
        if slip > SLIP_TOLERANCE:
            raise GraspFailure(f"{stage}: the cube slipped {slip * 100:.1f} cm in the gripper while carried")
        sim.grip(arm, False, 0.4)
        sim.move(arm, retreat, seconds=0.6)
        if go_home:
            sim.move(arm, [arm.home])

    def resting_in(self, tray: dict) -> tuple[bool, float]:
        """(whether the cube is inside the tray object's box, up to a cube's height above it; its speed in m/s)."""
        model, data = self.sim.model, self.sim.data
        body = model.body(tray["body"]).id
        rot = data.xmat[body].reshape(3, 3)
        local = rot.T @ (self.position() - data.xpos[body])
        half = np.asarray(tray["dimensions"], float) / 2
        velocity = np.zeros(6)
        mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_BODY, self.body, velocity, 0)
        inside = bool(np.all(np.abs(local[:2]) < half[:2]) and -half[2] < local[2] < half[2] + 2 * self.half_height)
        return inside, float(np.linalg.norm(velocity[3:]))

    def release_point(self, tray: dict) -> np.ndarray:
        """Where to release the cube over a tray: its centre, just above its floor."""
        point = np.asarray(tray["position"], float).copy()
        bottom = point[2] - float(np.abs(quat_to_matrix(tray["quaternion"])[2]) @ (np.asarray(tray["dimensions"], float) / 2))
        point[2] = bottom + self.half_height + PLACE_CLEARANCE
        return point
