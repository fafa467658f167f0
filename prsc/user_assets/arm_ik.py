"""Top-down IK for any arm in any MuJoCo model (docs/assets.md): damped least squares on
the arm's joints that puts its tool frame at a point with the tool's +z straight down, any
yaw. The reach cell of `reachable by` (prsc/constraints/arm_reach.py) is built with it on
the arm alone, and the example controller for any arm (prsc/runner/visit.py) runs
it on the compiled scene. Foundation module: mujoco is imported by the caller's model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

POSITION_TOLERANCE = 0.002  # m
ANGLE_TOLERANCE = 0.02  # rad
DOWN = np.array([0.0, 0.0, -1.0])
# m above a point where the tool must also stand top-down for the point to count as reached:
# what `reachable by` certifies for a file arm (constraints/arm_reach.py) and where the example
# controller (prsc/runner/visit.py) comes from before going down.
REACH_APPROACH = 0.12
RESTARTS = 4  # starts drawn within the joint limits where home's fail: a 7-joint arm's IK from
# home alone misses a third of the points it reaches top-down (KUKA iiwa: 109 of 150 found)
STALL_ITERATIONS = 20  # a solve whose error has not fallen by STALL_GAIN in this many steps has stalled
STALL_GAIN = 0.01  # (at a joint limit or a singular pose); most failing solves stall, and ran 80 steps
BELOW_BASE = 0.02  # m a link's origin may sink below the base's: UR arms' elbow-down answers went 0.2 m into the table
LIMIT_MARGIN = 0.02  # rad or m kept from every joint limit: a simulated servo held against its
# limit stops short of it (the limit constraint is soft), so a pose at a limit would miss.


@dataclass(frozen=True)
class ArmFrames:
    """Where an arm lives in a model: its joints' qpos and dof addresses and its tool."""

    qpos: np.ndarray  # qpos address of each arm joint (hinge or slide), in order
    dofs: np.ndarray  # dof address of each
    lower: np.ndarray  # joint limits less LIMIT_MARGIN (-inf/inf when unlimited)
    upper: np.ndarray
    tool: int  # site id or body id
    tool_is_site: bool
    bodies: tuple[int, ...] = ()  # the bodies the joints move (each joint's body)
    base: int = 0  # the body the first joint's body hangs from: the arm's base

    @staticmethod
    def of(model, joints: list[str], tool: str) -> "ArmFrames":
        """The frames of joints `joints` and tool `tool` (a site, else a body) of `model`."""
        ids = [model.joint(name).id for name in joints]
        limited = model.jnt_limited[ids].astype(bool)
        try:
            tool_id, is_site = model.site(tool).id, True
        except KeyError:
            tool_id, is_site = model.body(tool).id, False
        low, high = model.jnt_range[ids, 0], model.jnt_range[ids, 1]
        # A range narrower than both margins (gym-aloha's vx300s has one) is held at its middle.
        middle = (low + high) / 2
        return ArmFrames(
            qpos=model.jnt_qposadr[ids].copy(), dofs=model.jnt_dofadr[ids].copy(),
            lower=np.where(limited, np.minimum(low + LIMIT_MARGIN, middle), -np.inf),
            upper=np.where(limited, np.maximum(high - LIMIT_MARGIN, middle), np.inf),
            tool=tool_id, tool_is_site=is_site,
            bodies=tuple(int(model.jnt_bodyid[j]) for j in ids), base=int(model.body_parentid[model.jnt_bodyid[ids[0]]]),
        )

    def above_base(self, data) -> bool:
        """Whether every body the joints move has its origin above the base's, less BELOW_BASE
        (after kinematics): an arm standing on a table keeps its links out of the table."""
        floor = data.xpos[self.base, 2] - BELOW_BASE
        return bool(all(data.xpos[body, 2] >= floor for body in self.bodies))

    def heading(self, data, root: np.ndarray) -> float:
        """The azimuth of the tool about the point `root` (the arm's root) in `data` (after kinematics)."""
        tool = self.tool_pose(data)[0] - root
        return math.atan2(tool[1], tool[0])

    def tool_pose(self, data) -> tuple[np.ndarray, np.ndarray]:
        """The tool's world position and rotation matrix in `data` (after kinematics)."""
        if self.tool_is_site:
            return data.site_xpos[self.tool].copy(), data.site_xmat[self.tool].reshape(3, 3).copy()
        return data.xpos[self.tool].copy(), data.xmat[self.tool].reshape(3, 3).copy()


DAMPING = 1e-4 * np.eye(6)  # of the damped least-squares step


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """np.cross of two 3-vectors, the same arithmetic at a twentieth of its cost (most of an IK step's)."""
    a0, a1, a2 = a.tolist()
    b0, b1, b2 = b.tolist()
    return np.array((a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0))


def solve_top_down(model, data, arm: ArmFrames, goal: np.ndarray, q: np.ndarray,
                   iterations: int = 80, facing: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, bool]:
    """(arm joint values, reached) for the tool at world point `goal` pointing down, from `q`;
    `facing` (a horizontal vector in the tool's frame, a horizontal world direction) fixes the
    yaw too: the tool's vector then points along the direction (a gripper's closing axis
    across a box's faces).

    Writes `data.qpos` of the arm's joints as it goes (other joints stay); call it on a
    scratch MjData."""
    import mujoco

    jacp, jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
    # Turning about the vertical keeps a top-down pose, so without `facing` that turn is free.
    horizontal = np.eye(3) - np.outer(DOWN, DOWN) if facing is None else np.eye(3)
    q = np.clip(np.array(q, float), arm.lower, arm.upper)
    wanted_side = None if facing is None else _cross(DOWN, facing[1])  # the wanted frame's third axis
    best, since_best = math.inf, 0
    for _ in range(iterations):
        data.qpos[arm.qpos] = q
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        position, rotation = arm.tool_pose(data)
        error_p = goal - position
        axis = rotation[:, 2]
        miss, tilt = float(np.linalg.norm(error_p)), math.acos(min(1.0, max(-1.0, -axis[2])))
        turn = _cross(axis, DOWN)
        if facing is not None:
            # The rotation from the tool's frame to the wanted one, from all three axes (half the
            # sum of their cross products): the two given ones alone count a tilt twice.
            pointing = rotation @ facing[0]
            turn = 0.5 * (turn + _cross(pointing, facing[1]) + _cross(_cross(axis, pointing), wanted_side))
            tilt += math.acos(min(1.0, max(-1.0, float(pointing @ facing[1]))))
        if miss < POSITION_TOLERANCE and tilt < ANGLE_TOLERANCE:
            return q, True
        if miss + tilt < best * (1 - STALL_GAIN):
            best, since_best = miss + tilt, 0
        else:
            since_best += 1
            if since_best == STALL_ITERATIONS:
                return q, False
        if arm.tool_is_site:
            mujoco.mj_jacSite(model, data, jacp, jacr, arm.tool)
        else:
            mujoco.mj_jacBody(model, data, jacp, jacr, arm.tool)
        jac = np.concatenate([jacp[:, arm.dofs], horizontal @ jacr[:, arm.dofs]])
        error = np.concatenate([error_p, horizontal @ turn])
        step = jac.T @ np.linalg.solve(jac @ jac.T + DAMPING, error)
        q = np.clip(q + step, arm.lower, arm.upper)
    return q, False


def turned(home: np.ndarray, arm: ArmFrames, heading: float, azimuth: float) -> np.ndarray:
    """Home with the first joint turned by `azimuth - heading` (within its limits): the tool, heading
    `heading` about the arm's root at home, then heads towards `azimuth` (for the base yaw joint
    most arms have; for another first joint it is one more start)."""
    q = np.array(home, dtype=float)
    turn = (azimuth - heading + math.pi) % (2 * math.pi) - math.pi
    q[0] = float(np.clip(q[0] + turn, arm.lower[0], arm.upper[0]))
    return q


def random_starts(arm: ArmFrames, home: np.ndarray, count: int) -> list[np.ndarray]:
    """`count` joint vectors drawn within the limits (within pi of home where a joint has none), the same every call."""
    if not count:
        return []
    lower = np.where(np.isfinite(arm.lower), arm.lower, home - math.pi)
    upper = np.where(np.isfinite(arm.upper), arm.upper, home + math.pi)
    return list(np.random.default_rng(0).uniform(lower, upper, (count, len(home))))


def reach_top_down(model, data, arm: ArmFrames, goal: np.ndarray, seed: np.ndarray, home: np.ndarray,
                   approach: float, restarts: int = 0) -> tuple[np.ndarray, bool]:
    """The point `approach` above `goal`, then `goal` itself, each top-down; from `seed`,
    else from home and two bent starts (a straight-up home is singular for a top-down pose),
    else from `restarts` starts drawn within the joint limits (the same ones every call)."""
    above = goal + np.array([0.0, 0.0, approach])
    bend = np.where(np.arange(len(home)) % 2, 0.5, -0.5)
    starts = [seed, home, home + bend, home - bend] if not np.array_equal(seed, home) else [home, home + bend, home - bend]
    starts += random_starts(arm, home, restarts)
    for start in starts:
        q, ok = solve_top_down(model, data, arm, above, start)
        if ok and arm.above_base(data):
            q, ok = solve_top_down(model, data, arm, goal, q)
            if ok and arm.above_base(data):
                return nearest_turn(q, home, arm), True
    return seed, False


def nearest_turn(q: np.ndarray, home: np.ndarray, arm: ArmFrames) -> np.ndarray:
    """`q` with every joint turned by whole turns to the value nearest home that its limits allow:
    the same pose, which a servo reaches without swinging the arm round (a UR's 5.27 rad is -1.01)."""
    turns = np.round((home - q) / (2 * math.pi))
    turned = q + 2 * math.pi * turns
    return np.where((turned >= arm.lower) & (turned <= arm.upper), turned, q)
