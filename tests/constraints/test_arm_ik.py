"""prsc/user_assets/arm_ik.py's own arithmetic: its 3-vector cross product is numpy's, bit for bit (the
reach of every arm, cached by file content, must not change with it), and a `facing` solve
turns the tool's given axis onto the world direction while it points down."""

from __future__ import annotations

import math

import numpy as np
import pytest

from prsc.user_assets.arm_ik import ArmFrames, _cross, solve_top_down


def _arm():
    """A five-joint arm (yaw, three pitches, a roll about the tool's axis), built with MjSpec."""
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
    return spec.compile()


def test_the_cross_product_is_numpys_bit_for_bit():
    rng = np.random.default_rng(3)
    for a, b in zip(rng.normal(size=(2000, 3)) * rng.choice([1e-9, 1.0, 1e6], (2000, 1)), rng.normal(size=(2000, 3))):
        assert np.array_equal(_cross(a, b), np.cross(a, b))


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
