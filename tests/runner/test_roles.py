"""Roles come from classes and positions, never from object names."""

from __future__ import annotations

import pytest

from prsc.runner.roles import find_roles
from prsc.errors import PrscError


def test_roles_of_the_table_cube_scene(table_cube):
    roles = find_roles(table_cube)
    assert (roles.left_robot["name"], roles.right_robot["name"]) == ("r1", "r2")
    assert (roles.source_tray["name"], roles.target_tray["name"]) == ("tr_1", "tr_2")
    assert roles.cube["name"] == "c1" and roles.camera["name"] == "camera"


def test_roles_ignore_names_and_order(table_cube):
    renamed = {"r1": "zeta", "r2": "alpha", "tr_1": "b_tray", "tr_2": "a_tray", "c1": "thing"}
    for obj in table_cube["objects"]:
        obj["name"] = renamed.get(obj["name"], obj["name"])
    table_cube["objects"].reverse()
    roles = find_roles(table_cube)
    assert roles.left_robot["name"] == "zeta"  # x = -0.4
    assert roles.right_robot["name"] == "alpha"
    assert roles.source_tray["name"] == "b_tray"  # the tray under the cube
    assert roles.target_tray["name"] == "a_tray"


def test_missing_roles_are_named(table_cube):
    table_cube["objects"] = [o for o in table_cube["objects"] if o["class"] not in ("Camera", "Tray")]
    with pytest.raises(PrscError) as error:
        find_roles(table_cube)
    message = error.value.message
    assert "2 Trays (found 0)" in message and "1 Camera (found 0)" in message
    assert "Robot" not in message.split("needs")[1].split(";")[0]


def test_a_robot_that_is_no_arm_is_refused(table_cube):
    """Any arm fills a robot's role (tests/runner/test_handover_any_arm.py); a model that names
    neither the built-in arm nor an arm's file does not."""
    table_cube["objects"][1]["model"] = "ur5"
    with pytest.raises(PrscError, match="has model 'ur5', which is no arm: the handover drives two arms with grippers"):
        find_roles(table_cube)


def test_subclasses_fill_roles_through_the_scene_class_map(table_cube):
    cube = next(o for o in table_cube["objects"] if o["class"] == "Cube")
    cube["class"] = "RedCube"
    with pytest.raises(PrscError, match=r"1 Cube \(found 0\)"):
        find_roles(table_cube)
    table_cube["classes"] = {"RedCube": ["Cube", "Object"], "Tray": ["Object"]}
    assert find_roles(table_cube).cube["name"] == cube["name"]
