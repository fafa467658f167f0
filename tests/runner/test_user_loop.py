"""The shipped controllers called from a user's own loop, exactly as docs/learning.md shows
(prsc.load -> scene -> prsc.mujoco_model -> MjData at `home` + mj_forward -> controller):
the library API's scenes are the ones `prsc run` hands a controller (each object with its
`body`), so neither controller fails with KeyError 'body', and both succeed where `prsc run`
does. Without mj_forward the handover's IK read a zero tool pose ("IK residual nan cm")."""

from __future__ import annotations

from pathlib import Path

import pytest

import prsc
from prsc.backends.names import with_body_names

SPECS = Path(__file__).resolve().parents[2] / "specs"


def _episode(scenario, controller, index: int) -> dict:
    """One episode as a user writes it (docs/learning.md, "Your own loop")."""
    import mujoco

    scene = scenario.scene(seed=0, index=index)
    model = prsc.mujoco_model(scene)
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    return controller(scene, model, data)


def test_library_scenes_carry_the_body_names_prsc_run_gives():
    scenario = prsc.load(SPECS / "table_cube.prs")
    scene = scenario.scene(seed=0, index=0)
    assert all("body" in o for o in scene["objects"])
    assert scene == with_body_names(scene)
    assert next(iter(scenario.scenes(0, 1))) == scene


def test_the_handover_succeeds_from_a_users_loop():
    from prsc.runner.handover import handover

    # Scene 0 is a perception fault under `prsc run` too (its cube hidden from the camera); 1 and 2 succeed.
    result = _episode(prsc.load(SPECS / "table_cube.prs"), handover, 1)
    assert result["outcome"] == "success", result


def test_pick_succeeds_from_a_users_loop():
    pybullet_data = pytest.importorskip("pybullet_data")
    from prsc.runner.pick import pick

    scenario = prsc.load(SPECS / "pybullet_arm" / "franka_pick.prs", include_dirs=[pybullet_data.getDataPath()])
    # Scene 16: c2 near the arm's base, where the joint-space move from the arm standing straight
    # up to the approach swept the fingers into it (pick's CLEARANCE).
    result = _episode(scenario, pick, 16)
    assert result["outcome"] == "picked", result
