"""The handover drives any two arms with grippers (prsc/runner/motion.py): pybullet's Franka
URDF twice (specs/pybullet_arm/franka_handover.prs), called from a user's own loop as
docs/learning.md shows, hands the cube over, each arm's ready pose holding its hand ahead of
its base; two arms without grippers are refused by name."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import prsc
from prsc.errors import PrscError
from prsc.geometry.rotations import quat_to_matrix

pybullet_data = pytest.importorskip("pybullet_data")
SPEC = Path(__file__).resolve().parents[2] / "specs" / "pybullet_arm" / "franka_handover.prs"


def _compiled(scenario, index: int):
    """Scene `index` (seed 0), its model and its data at `home`, forward-computed (docs/learning.md)."""
    import mujoco

    scene = scenario.scene(seed=0, index=index)
    model = prsc.mujoco_model(scene)
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    return scene, model, data


@pytest.fixture(scope="module")
def frankas():
    return prsc.load(SPEC, include_dirs=[pybullet_data.getDataPath()])


def test_two_franka_urdfs_hand_the_cube_over_from_a_users_loop(frankas):
    from prsc.runner.handover import handover

    scene, model, data = _compiled(frankas, 1)
    result = handover(scene, model, data)
    assert result["outcome"] == "success", result
    tray = next(o for o in scene["objects"] if o["name"] == "tr_2")
    assert np.all(np.abs(np.subtract(result["cube_final"][:2], tray["position"][:2])) < np.divide(tray["dimensions"][:2], 2))


def test_each_frankas_ready_pose_holds_its_hand_ahead_of_its_base(frankas):
    """`with joint` sets the built-in arm's home; the hand then stands 0.3 m ahead (+y in the
    robot object's frame) of the base, on the base's own line."""
    from prsc.runner.motion import Arm
    from prsc.runner.roles import find_roles

    scene, model, data = _compiled(frankas, 0)
    roles = find_roles(scene)
    for robot in (roles.left_robot, roles.right_robot):
        arm = Arm.of(robot, model, data)
        hand = quat_to_matrix(robot["quaternion"]).T @ (arm.frames.tool_pose(data)[0] - arm.root)
        assert hand[1] > 0.25 and abs(hand[0]) < 0.01, (robot["name"], hand)


def test_arms_without_grippers_are_refused_by_name(tmp_path):
    """pybullet's KUKA iiwa has no gripper: the handover names the robot and what it lacks."""
    from prsc.runner.handover import handover

    text = SPEC.read_text().replace('"franka_panda/panda.urdf"', '"kuka_iiwa/model.urdf"')
    text = "\n".join(line for line in text.splitlines() if "with joint" not in line).replace(
        ', with tcp "panda_grasptarget",', "")
    spec = tmp_path / "kuka_handover.prs"
    spec.write_text(text)
    scene, model, data = _compiled(prsc.load(spec, include_dirs=[pybullet_data.getDataPath()]), 0)
    with pytest.raises(PrscError, match=r"Robot 'r1' has no gripper: .*the handover needs two arms with grippers"):
        handover(scene, model, data)
