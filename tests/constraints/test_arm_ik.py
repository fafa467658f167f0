"""prsc/user_assets/arm_ik.py, the one IK (mink): a `facing` solve turns the tool's given axis onto
the world direction while it points down; limits, links below the base, whole turns."""

from __future__ import annotations

import math

import numpy as np
import pytest

from prsc.user_assets.arm_ik import ArmFrames, solve_top_down


def _arm():
    """A five-joint arm (yaw, three pitches, a roll about the tool's axis), compiled."""
    return _arm_spec().compile()


def _arm_spec():
    """The five-joint arm's MjSpec."""
    import mujoco

    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    body = spec.worldbody.add_body(name="base")
    links = [  # (name, joint axis, offset from the parent, capsule to the child)
        ("base", (0, 0, 1), (0, 0, 0), (0, 0, 0.3)), ("upper", (0, 1, 0), (0, 0, 0.3), (0.3, 0, 0)),
        ("fore", (0, 1, 0), (0.3, 0, 0), (0.25, 0, 0)), ("wrist", (0, 1, 0), (0.25, 0, 0), (0.05, 0, 0)),
        ("hand", (1, 0, 0), (0.05, 0, 0), (0.03, 0, 0)),
    ]
    for k, (name, axis, offset, length) in enumerate(links):
        if k:
            body = body.add_body(name=name, pos=offset)
        body.add_joint(name=f"joint{k}", axis=axis, range=(-3.14, 3.14) if k in (0, 4) else (-2.5, 2.5))
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_CAPSULE, fromto=(0, 0, 0, *length), size=(0.02, 0, 0), mass=0.5)
    body.add_site(name="tcp", pos=(0.05, 0, 0), zaxis=(1, 0, 0))
    return spec


def test_a_facing_solve_points_down_and_turns_the_given_axis_onto_the_direction():
    import mujoco

    model = _arm()
    data = mujoco.MjData(model)
    arm = ArmFrames.of(model, [f"joint{k}" for k in range(5)], "tcp")
    start = np.array([0.0, 0.2, 0.8, 0.57, 0.0])
    for yaw in np.linspace(-1.4, 1.4, 8):
        # Either way along a direction (a gripper closes alike): the solve does not wrap a
        # joint round, so one of the two may lie beyond the roll joint's limit from here.
        for direction in (np.array([math.cos(yaw), math.sin(yaw), 0.0]), -np.array([math.cos(yaw), math.sin(yaw), 0.0])):
            q, ok = solve_top_down(model, data, arm, np.array([0.35, 0.1, 0.1]), start,
                                   facing=(np.array([1.0, 0.0, 0.0]), direction))
            if ok:
                break
        assert ok, yaw
        position, rotation = arm.tool_pose(data)
        assert np.linalg.norm(position - [0.35, 0.1, 0.1]) < 0.002
        assert rotation[2, 2] < -math.cos(0.02) and rotation[:, 0] @ direction > math.cos(0.02)


def test_a_joint_range_narrower_than_the_margins_is_held_at_its_middle():
    """gym-aloha's vx300s has a joint whose range is narrower than the two 0.02 margins: its
    limits were crossed (lower > upper) and drawing random starts raised numpy's ValueError."""
    import mujoco

    from prsc.user_assets.arm_ik import ArmFrames, random_starts

    model = mujoco.MjModel.from_xml_string(
        '<mujoco><compiler angle="radian"/><worldbody><body><joint name="a" range="-1 1" limited="true"/><geom size="0.1"/>'
        '<body><joint name="b" type="slide" range="0.01 0.03" limited="true"/><geom size="0.1"/>'
        '<site name="tool"/></body></body></worldbody></mujoco>')
    arm = ArmFrames.of(model, ["a", "b"], "tool")
    assert arm.lower.tolist() == pytest.approx([-0.98, 0.02]) and arm.upper.tolist() == pytest.approx([0.98, 0.02])
    starts = random_starts(arm, np.array([0.0, 0.02]), 4)
    assert all(-0.98 <= q[0] <= 0.98 and q[1] == pytest.approx(0.02) for q in starts)


def test_a_pose_with_a_link_below_the_base_is_refused_and_angles_come_nearest_home():
    """UR arms' top-down answers put the elbow 0.2 m into the table the arm stands on, or turned a
    joint by a whole turn (5.27 rad for -1.01), which a servo swings the arm round to reach."""
    import mujoco

    from prsc.user_assets.arm_ik import ArmFrames, nearest_turn, reach_top_down

    model = mujoco.MjModel.from_xml_string(
        '<mujoco><compiler angle="radian"/><worldbody><body name="base" pos="0 0 0.5"><geom size="0.05"/>'
        '<body name="upper"><joint name="shoulder" axis="0 1 0" range="-6.3 6.3" limited="true"/>'
        '<geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02"/>'
        '<body name="fore" pos="0.3 0 0"><joint name="elbow" axis="0 1 0" range="-3 3" limited="true"/>'
        '<geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02"/>'
        '<body name="hand" pos="0.3 0 0"><joint name="wrist" axis="0 1 0" range="-3 3" limited="true"/>'
        '<geom size="0.02"/><site name="tool" pos="0 0 0"/></body></body></body></body></worldbody></mujoco>')
    data = mujoco.MjData(model)
    arm = ArmFrames.of(model, ["shoulder", "elbow", "wrist"], "tool")
    for shoulder, above in ((0.5, False), (-0.5, True)):  # +y turns the arm's +x down
        data.qpos[:] = [shoulder, 0.0, 0.0]
        mujoco.mj_kinematics(model, data)
        assert arm.above_base(data) is above
    home = np.array([-0.3, 0.6, 1.2])
    assert nearest_turn(np.array([5.27, 0.2, 0.3]), home, arm)[0] == pytest.approx(5.27 - 2 * math.pi)
    # A point beside the base at its height: every answer keeps the links above the base.
    q, ok = reach_top_down(model, data, arm, np.array([0.35, 0.0, 0.5]), home, home, 0.12, restarts=8)
    data.qpos[:] = q
    mujoco.mj_kinematics(model, data)
    assert ok and arm.above_base(data)


def _file_arm(path: str, tool: str | None):
    """(model, frames, home, root) of an arm from pybullet_data, as `reachable by` reads it."""
    from dataclasses import replace
    from pathlib import Path

    import mujoco
    import pybullet_data

    from prsc.user_assets.asset_files import asset_spec, describe_asset

    asset = describe_asset(Path(pybullet_data.getDataPath()) / path)
    asset = replace(asset, tcp=tool) if tool else asset
    model = asset_spec(asset.source).compile()
    frames = ArmFrames.of(model, [j.name for j in asset.joints], str(asset.tcp))
    data = mujoco.MjData(model)
    data.qpos[frames.qpos] = [j.home for j in asset.joints]
    mujoco.mj_kinematics(model, data)
    return model, frames, data.qpos[frames.qpos].copy(), data.xpos[model.body(asset.root).id].copy()


@pytest.mark.parametrize("path,tool", [("xarm/xarm6_robot.urdf", None), ("kuka_iiwa/model.urdf", None),
                                       ("franka_panda/panda.urdf", "panda_grasptarget")])
def test_the_ik_reaches_top_down_points_of_held_out_arms_to_a_tenth_of_a_mm(path, tool):
    """Points the tool reaches top-down (random joint values within the limits, turned exactly
    down by scipy and kept with every link above the base) are reached by `reach_top_down` as
    `reachable by` asks it, each well inside the 2 mm tolerance: mink goes on to 0.1 mm (the
    hand-written damped least squares stopped at the tolerance: median 0.2-1.8 mm)."""
    import mujoco
    from scipy.optimize import least_squares

    from prsc.user_assets.arm_ik import RESTARTS, reach_top_down, turned

    model, arm, home, root = _file_arm(path, tool)
    data = mujoco.MjData(model)
    lower, upper = arm.lower, np.maximum(arm.upper, arm.lower + 1e-9)

    def pose(q):
        data.qpos[arm.qpos] = q
        mujoco.mj_kinematics(model, data)
        return arm.tool_pose(data)

    rng, targets = np.random.default_rng(5), []
    while len(targets) < 4:
        q = rng.uniform(lower, upper)
        if pose(q)[1][2, 2] < -math.cos(0.35):
            fit = least_squares(lambda x: pose(x)[1][:, 2] + [0.0, 0.0, 1.0], q, bounds=(lower, upper), xtol=1e-12)
            position, rotation = pose(fit.x)
            if rotation[2, 2] < -math.cos(1e-4) and arm.fits(model, data) and position[2] > root[2] - 0.1:
                targets.append(position)
    heading = math.atan2(*(pose(home)[0] - root)[1::-1])
    for goal in targets:
        start = turned(home, arm, heading, math.atan2(*(goal - root)[1::-1]))
        q, ok = reach_top_down(model, data, arm, goal, start, start, 0.0, RESTARTS)
        position, rotation = pose(q)
        assert ok, (path, goal)
        assert np.linalg.norm(position - goal) < 1e-4 and rotation[2, 2] < -math.cos(1e-3)
        assert np.all((q >= arm.lower - 1e-9) & (q <= arm.upper + 1e-9)) and arm.fits(model, data)


def test_a_pose_with_the_hand_in_the_base_does_not_fit():
    """A top-down answer beside pybullet's Franka's base (0.1 m from it at its height) that puts
    link 6 3 cm into link 1 and the hand into the base is refused; an ordinary one is not."""
    import mujoco

    from prsc.user_assets.arm_ik import reach_top_down

    model, arm, home, root = _file_arm("franka_panda/panda.urdf", "panda_grasptarget")
    data = mujoco.MjData(model)
    data.qpos[arm.qpos] = [-0.559, 0.373, -0.414, -3.073, 2.643, 2.83, -1.705, 0.02, 0.02]
    mujoco.mj_kinematics(model, data)
    assert arm.above_base(data) and arm.self_collides(model, data) and not arm.fits(model, data)
    q, ok = reach_top_down(model, data, arm, root + [0.5, 0.0, 0.0], home, home, 0.12, restarts=4)
    assert ok and not arm.self_collides(model, data)


def test_a_solve_moves_the_arm_alone():
    """On a model with more than the arm (a free cube, a joint off the arm), a solve moves only
    the arm's joints: mink's DofFreezingTask holds the rest exactly."""
    import mujoco

    spec = _arm_spec()
    cube = spec.worldbody.add_body(name="cube", pos=(0.5, 0.3, 0.1))
    cube.add_freejoint()
    cube.add_geom(size=(0.02, 0.02, 0.02), type=mujoco.mjtGeom.mjGEOM_BOX)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_resetData(model, data)
    arm = ArmFrames.of(model, [f"joint{k}" for k in range(4)], "tcp")  # joint4, the roll, is held
    data.qpos[model.joint("joint4").qposadr[0]] = 0.3
    before = data.qpos.copy()
    q, ok = solve_top_down(model, data, arm, np.array([0.35, 0.1, 0.1]), np.array([0.0, 0.2, 0.8, 0.57]))
    assert ok
    others = np.setdiff1d(np.arange(model.nq), arm.qpos)
    assert np.array_equal(data.qpos[others], before[others]) and not np.array_equal(data.qpos[arm.qpos], before[arm.qpos])


def test_a_pose_solve_reaches_any_orientation_the_arm_can_take():
    """`solve_pose` (the handover's hand held at a given rotation, not only top-down): poses of
    random joint values of the five-joint arm are reached from 0.2 rad off on every joint (a local
    solve), to 0.1 mm and 0.001 rad, and a pose 2 m away is not."""
    import mujoco

    from prsc.user_assets.arm_ik import solve_pose

    model = _arm()
    data = mujoco.MjData(model)
    arm = ArmFrames.of(model, [f"joint{k}" for k in range(5)], "tcp")
    rng = np.random.default_rng(1)
    for _ in range(5):
        data.qpos[:] = rng.uniform(-1.0, 1.0, 5)
        mujoco.mj_kinematics(model, data)
        position, rotation = arm.tool_pose(data)
        q, ok = solve_pose(model, data, arm, position, rotation, data.qpos + 0.2)
        reached, turned = arm.tool_pose(data)
        assert ok and np.linalg.norm(reached - position) < 1e-4 and np.trace(turned.T @ rotation) > 1 + 2 * math.cos(1e-3)
    assert not solve_pose(model, data, arm, np.array([2.0, 0.0, 0.3]), rotation, np.zeros(5))[1]
