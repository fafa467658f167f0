"""The shipped controllers called from a user's own loop, exactly as docs/learning.md shows
(choose_gl_backend before mujoco is imported; prsc.load -> scene -> prsc.mujoco_model -> MjData
at `home` + mj_forward -> controller):
the library API's scenes are the ones `prsc run` hands a controller (each object with its
`body`), so neither controller fails with KeyError 'body', and both succeed where `prsc run`
does. Without mj_forward the handover's IK read a zero tool pose ("IK residual nan cm")."""

from __future__ import annotations

import os
import re
import subprocess
import sys
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


def _learning_example() -> str:
    """The code block of docs/learning.md's "Your own loop with a shipped controller"."""
    text = (SPECS.parent / "docs" / "learning.md").read_text(encoding="utf-8")
    section = text[text.index("## Your own loop with a shipped controller"):]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_the_docs_loop_runs_the_handover_in_a_fresh_shell():
    """The docs' block as a user pastes it, in an environment without MUJOCO_GL (conftest sets
    one for the suite): scenes 0 and 1 succeed, as under `prsc run` (scene 0 was a perception
    fault, its cube hidden from the camera, before the library Panda's box became its file's)."""
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    done = subprocess.run([sys.executable, "-c", _learning_example()], cwd=SPECS.parent, env=env,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    outcomes = [re.search(r"'outcome': '(\w+)'", line).group(1) for line in done.stdout.splitlines()]
    assert outcomes == ["success", "success"], done.stdout


def test_pick_succeeds_from_a_users_loop():
    pybullet_data = pytest.importorskip("pybullet_data")
    from prsc.runner.pick import pick

    scenario = prsc.load(SPECS / "pybullet_arm" / "franka_pick.prs", include_dirs=[pybullet_data.getDataPath()])
    # Scene 16: c2 near the arm's base, where the joint-space move from the arm standing straight
    # up to the approach swept the fingers into it (pick's CLEARANCE).
    result = _episode(scenario, pick, 16)
    assert result["outcome"] == "picked", result
