"""prsc/arm_ik.py's own arithmetic: its 3-vector cross product is numpy's, bit for bit (the
reach of every arm, cached by file content, must not change with it), and a `facing` solve
turns the tool's given axis onto the world direction while it points down."""

from __future__ import annotations

import math

import numpy as np
import pytest

from prsc.arm_ik import ArmFrames, _cross, solve_top_down


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

    from prsc.arm_ik import ArmFrames, random_starts

    model = mujoco.MjModel.from_xml_string(
        '<mujoco><compiler angle="radian"/><worldbody><body><joint name="a" range="-1 1" limited="true"/><geom size="0.1"/>'
        '<body><joint name="b" type="slide" range="0.01 0.03" limited="true"/><geom size="0.1"/>'
        '<site name="tool"/></body></body></worldbody></mujoco>')
    arm = ArmFrames.of(model, ["a", "b"], "tool")
    assert arm.lower.tolist() == pytest.approx([-0.98, 0.02]) and arm.upper.tolist() == pytest.approx([0.98, 0.02])
    starts = random_starts(arm, np.array([0.0, 0.02]), 4)
    assert all(-0.98 <= q[0] <= 0.98 and q[1] == pytest.approx(0.02) for q in starts)
