"""Top-down IK for any arm in any MuJoCo model (docs/assets.md): mink's differential IK on the
arm's joints (prsc/user_assets/arm_qp.py: a FrameTask within the joints' limits, every other
joint of the model held) that puts its tool frame at a point with the tool's +z straight down,
any yaw, or also a given yaw (`facing`), or at any given rotation (`solve_pose`). It is the one
IK of prsc: the reach cell of `reachable by` (prsc/constraints/arm_reach.py) is built with it on
the arm alone, and the controllers (prsc/runner/visit.py, pick.py) run it on a scratch copy of
the compiled scene.
"""

from __future__ import annotations

import math

import numpy as np

from prsc.user_assets.arm_frames import ArmFrames

POSITION_TOLERANCE = 0.002  # m: reached means within this of the point
ANGLE_TOLERANCE = 0.02  # rad: and the tool's axes within this of the wanted ones
# A solve goes on past the tolerances to these (a few more steps of a quadratically converging
# method): the controllers' waypoints then lie a few hundredths of a mm from the points.
CONVERGED_POSITION = 1e-4  # m
CONVERGED_ANGLE = 1e-3  # rad
ITERATIONS = 80  # mink steps a solve may take
DOWN = np.array([0.0, 0.0, -1.0])
# m above a point where the tool must also stand top-down for the point to count as reached:
# what `reachable by` certifies for a file arm (constraints/arm_reach.py) and where the example
# controller (prsc/runner/visit.py) comes from before going down.
REACH_APPROACH = 0.12
RESTARTS = 4  # starts drawn within the joint limits where home's fail: a 7-joint arm's IK from
# home alone misses a third of the points it reaches top-down (KUKA iiwa: 109 of 150 found)
# A solve whose error has not fallen by STALL_GAIN in STALL_ITERATIONS steps has stalled (at a joint
# limit or a singular pose): most solves of a reach build fail (5,000 of 8,400), and a mink step is
# a QP; 10 steps keep the xArm6's ring (97.7 % of its reach, 0 points unreached) and build it in
# 10 s of CPU against 15 s with 20 (docs/assets.md, "The IK").
STALL_ITERATIONS = 10
STALL_GAIN = 0.01


def down_quaternion(rotation: np.ndarray) -> np.ndarray:
    """The quaternion (wxyz) of `rotation` turned the least way that points its +z straight down (its yaw kept)."""
    import mujoco

    axis = rotation[:, 2]
    sine, cosine = math.hypot(axis[0], axis[1]), -axis[2]  # the turn's axis is axis x DOWN = (-y, x, 0)
    if sine < 1e-9:  # down already, or straight up: then half a turn about the tool's x
        turn = np.array([1.0, 0.0, 0.0, 0.0]) if cosine > 0 else np.array([0.0, *rotation[:, 0]])
    else:
        half = math.atan2(sine, cosine) / 2
        turn = np.array([math.cos(half), -axis[1] * math.sin(half) / sine, axis[0] * math.sin(half) / sine, 0.0])
    current, turned_quaternion = np.empty(4), np.empty(4)
    mujoco.mju_mat2Quat(current, rotation.ravel())
    mujoco.mju_mulQuat(turned_quaternion, turn, current)
    return turned_quaternion


def facing_rotation(facing: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """The tool's rotation pointing down with its vector `facing[0]` (horizontal in the tool's
    frame) along the horizontal world direction `facing[1]`."""
    tool_vector = np.asarray(facing[0], float) / np.linalg.norm(facing[0])
    direction = np.asarray(facing[1], float) / np.linalg.norm(facing[1])
    in_tool = np.column_stack([tool_vector, np.cross([0.0, 0.0, 1.0], tool_vector), [0.0, 0.0, 1.0]])
    in_world = np.column_stack([direction, np.cross(DOWN, direction), DOWN])
    return in_world @ in_tool.T


def _miss(arm: ArmFrames, data, goal: np.ndarray, wanted: np.ndarray | None) -> tuple[float, float]:
    """How far the tool is from `goal` (m), and its rotation from `wanted` (rad), or from pointing down."""
    position, rotation = arm.tool_pose(data)
    if wanted is None:
        angle = math.acos(min(1.0, max(-1.0, -rotation[2, 2])))
    else:
        angle = math.acos(min(1.0, max(-1.0, (float(np.sum(rotation * wanted)) - 1.0) / 2.0)))
    return float(np.linalg.norm(goal - position)), angle


def solve_top_down(model, data, arm: ArmFrames, goal: np.ndarray, q: np.ndarray,
                   iterations: int = ITERATIONS, facing: tuple[np.ndarray, np.ndarray] | None = None
                   ) -> tuple[np.ndarray, bool]:
    """(arm joint values, reached) for the tool at world point `goal` pointing down, from `q`;
    `facing` (a horizontal vector in the tool's frame, a horizontal world direction) fixes the
    yaw too: the tool's vector then points along the direction (a gripper's closing axis
    across a box's faces).

    Solved by mink (prsc/user_assets/arm_qp.py) from `data`'s other joints; writes the answer
    to `data.qpos` of the arm's joints, with its kinematics (other joints stay): call it on a
    scratch MjData."""
    return _solve(model, data, arm, np.asarray(goal, float), q, None if facing is None else facing_rotation(facing),
                  iterations)


def solve_pose(model, data, arm: ArmFrames, goal: np.ndarray, rotation: np.ndarray, q: np.ndarray,
               iterations: int = ITERATIONS) -> tuple[np.ndarray, bool]:
    """(arm joint values, reached) for the tool at world point `goal` with world rotation matrix
    `rotation` (any orientation), from `q`; reached within POSITION_TOLERANCE and
    ANGLE_TOLERANCE. Writes `data` as `solve_top_down` does."""
    return _solve(model, data, arm, np.asarray(goal, float), q, np.asarray(rotation, float), iterations)


def _solve(model, data, arm: ArmFrames, goal: np.ndarray, q: np.ndarray, wanted: np.ndarray | None,
           iterations: int) -> tuple[np.ndarray, bool]:
    """mink's steps towards the tool at `goal` with rotation `wanted`, or pointing down at any yaw (None)."""
    import mujoco

    from prsc.user_assets.arm_qp import ArmProblem

    problem = ArmProblem.of(model, arm)
    configuration = problem.configuration
    qpos = data.qpos.copy()
    qpos[arm.qpos] = np.clip(np.array(q, float), arm.lower, arm.upper)
    problem.start(qpos, free_yaw=wanted is None)
    target = np.concatenate([np.zeros(4), goal])
    if wanted is not None:
        mujoco.mju_mat2Quat(target[:4], wanted.ravel())
    best, since_best = math.inf, 0
    for _ in range(iterations):
        miss, angle = _miss(arm, configuration.data, goal, wanted)
        if miss < CONVERGED_POSITION and angle < CONVERGED_ANGLE:
            break
        if miss + angle < best * (1 - STALL_GAIN):
            best, since_best = miss + angle, 0
        else:
            since_best += 1
            if since_best == STALL_ITERATIONS:
                break
        if wanted is None:  # the pose as it stands, turned down: its yaw is free
            target[:4] = down_quaternion(arm.tool_pose(configuration.data)[1])
        problem.step(target)
    q = np.clip(configuration.q[arm.qpos], arm.lower, arm.upper)
    data.qpos[arm.qpos] = q
    mujoco.mj_kinematics(model, data)
    miss, angle = _miss(arm, data, goal, wanted)
    return q, miss < POSITION_TOLERANCE and angle < ANGLE_TOLERANCE


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
    """The point `approach` above `goal`, then `goal` itself, each top-down by a pose that fits
    (`ArmFrames.fits`); from `seed`, else from home and two bent starts (a straight-up home is
    singular for a top-down pose), else from `restarts` starts drawn within the joint limits
    (the same ones every call)."""
    above = goal + np.array([0.0, 0.0, approach])
    bend = np.where(np.arange(len(home)) % 2, 0.5, -0.5)
    starts = [seed, home, home + bend, home - bend] if not np.array_equal(seed, home) else [home, home + bend, home - bend]
    starts += random_starts(arm, home, restarts)
    for start in starts:
        q, ok = solve_top_down(model, data, arm, above, start)
        if ok and arm.fits(model, data):
            q, ok = solve_top_down(model, data, arm, goal, q)
            if ok and arm.fits(model, data):
                return nearest_turn(q, home, arm), True
    return seed, False


def nearest_turn(q: np.ndarray, home: np.ndarray, arm: ArmFrames) -> np.ndarray:
    """`q` with every joint turned by whole turns to the value nearest home that its limits allow:
    the same pose, which a servo reaches without swinging the arm round (a UR's 5.27 rad is -1.01)."""
    turns = np.round((home - q) / (2 * math.pi))
    turned = q + 2 * math.pi * turns
    return np.where((turned >= arm.lower) & (turned <= arm.upper), turned, q)
