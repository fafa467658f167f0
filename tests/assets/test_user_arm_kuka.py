"""The KUKA iiwa through the checks of test_user_arms.py, in a file of its own so that the
suite's two workers (--dist loadfile) share the arms' reach builds."""

from __future__ import annotations

import pytest

from tests.assets.test_user_arms import (  # noqa: F401  (the same checks, collected here for the KUKA)
    compiled_arm,
    test_newton_loads_the_usd_with_every_joint_where_the_scene_starts_it,
    test_mjcf_has_every_joint_and_holds_the_scene_joint_values,
    test_reachable_cubes_are_reached_top_down_on_the_compiled_model,
    test_the_example_controller_drives_every_arm_by_its_own_names,
    test_the_reach_check_fails_on_a_cube_out_of_reach,
    test_the_sdf_states_where_every_joint_starts_and_pybullet_set_there_matches_mujoco,
    test_urdf_bundle_sdf_and_usd_carry_every_joint,
)


@pytest.fixture(scope="module")
def arm_output(tmp_path_factory):
    return compiled_arm("kuka_iiwa", tmp_path_factory)
