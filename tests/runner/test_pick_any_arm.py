"""The example pick for any arm with a gripper (prsc/runner/pick.py, docs/assets.md):
the gripper is found in the compiled model by forward kinematics, whatever drives it (a
URDF's finger joints with prsc's servos and a mimic, or the built-in Panda's tendon), and
each cube, at its own yaw, is lifted 12 cm and put back where it was. A cube wider than
the open gripper is not picked, and an arm without a gripper is refused by name."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from tests.backends import readback

pybullet_data = pytest.importorskip("pybullet_data")
DATA = Path(pybullet_data.getDataPath())
EPISODES = 2
ARMS = {  # the robot's class body, and its tool
    "franka_urdf": 'model: "franka_panda/panda.urdf"', "builtin_panda": "pass",
}


def _spec(folder: Path, arm: str, cube: str = "Cube", tcp: str = "") -> Path:
    """Two cubes at random yaws in front of the arm (placed by region, so no reach is built)."""
    spec = folder / "pick.prs"
    spec.write_text(textwrap.dedent(f"""\
        from tabletop import *
        table = Table on Vector3D(0, 0, 0), with width 1.8, with length 1.2, with height 0.75
        class Arm(Robot):
            {arm}
        class WideCube(Cube):  # wider than the Panda's fingers open (8 cm)
            width: 0.1
            length: 0.1
        arm = Arm on (top back table).position + Vector3D(0, 0.25, 0){tcp}
        c1 = {cube} completely on table, at Vector3D((-0.25, 0.25), (-0.05, 0.15), 0.77), facing (-45 deg, 45 deg)
        c2 = {cube} completely on table, at Vector3D((-0.25, 0.25), (-0.05, 0.15), 0.77), facing (-45 deg, 45 deg)
        """))
    return spec


def _prsc(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "prsc.cli", *args], capture_output=True, text=True, timeout=600,
                          env=env)


def _tcp(name: str) -> str:
    return ', with tcp "panda_grasptarget"' if name == "franka_urdf" else ""


EXAMPLE = Path(__file__).resolve().parents[2] / "specs" / "pybullet_arm" / "franka_pick.prs"


@pytest.mark.parametrize("name", ARMS)
def test_pick_lifts_every_cube_and_puts_it_back(name, tmp_path):
    """The Franka runs the example spec as its docstring says; the built-in Panda the same scene."""
    spec = EXAMPLE if name == "franka_urdf" else _spec(tmp_path, ARMS[name])
    done = _prsc("run", str(spec), "-I", str(DATA), "--controller", "prsc.runner.pick:pick",
                 "-n", str(EPISODES), "-o", str(tmp_path / "run"))
    assert done.returncode == 0, done.stderr
    records = [json.loads(line) for line in (tmp_path / "run" / "results.jsonl").read_text().splitlines()]
    assert [r["outcome"] for r in records] == ["picked"] * EPISODES, records
    assert min(r["lift"] for r in records) > 0.1


def _compiled(tmp_path: Path, spec: Path, build: Path | None = None) -> Path:
    """Scene 0 of `spec` as JSON and MJCF; with `build`, in that build folder, so that the
    arm's meshes are read here, not found in a cache, and nothing is printed but prsc's own
    warnings (trimesh warned, All-NaN slice, on the Franka's OBJ faces without UVs)."""
    import os

    done = _prsc("compile", str(spec), "-I", str(DATA), "-n", "1", "--target", "json,mjcf", "-o", str(tmp_path / "out"),
                 env={**os.environ, "PRSC_BUILD_DIR": str(build)} if build else None)
    assert done.returncode == 0, done.stderr
    if build:
        assert "Warning" not in done.stderr and list(build.rglob("*.obj")), done.stderr
    return tmp_path / "out" / "pick"


def test_the_gripper_is_found_by_its_kinematics_and_the_cube_is_put_back(tmp_path):
    """The URDF Panda's fingers close at their lower limit (0 m) and open at 0.04 m, along the
    hand's y axis; after the episode (ground truth) both cubes stand where they stood, level.
    Compiled in a fresh build folder: reading the Franka's meshes prints no numpy warnings."""
    from prsc.runner.arm_scene import SceneArm
    from prsc.runner.gripper import gripper_of
    from prsc.runner.pick import pick

    spec = _spec(tmp_path, ARMS["franka_urdf"], tcp=_tcp("franka_urdf"))
    scene, model, data = readback.scene_at_home(_compiled(tmp_path, spec, build=tmp_path / "build"), 0)
    arm = SceneArm.of(scene, model, "pick")
    gripper = gripper_of(model, arm.prefix, arm.frames, arm.tool)
    assert [model.actuator(a).name for a in gripper.actuators] == ["arm/panda_finger_joint1", "arm/panda_finger_joint2"]
    assert gripper.closed == pytest.approx([0.0, 0.0]) and gripper.opened == pytest.approx([0.04, 0.04])
    assert abs(gripper.closing[1]) == pytest.approx(1.0)
    start = {c: data.body(c).xpos.copy() for c in ("c1", "c2")}
    record = pick(scene, model, data)
    assert record["outcome"] == "picked", record
    for cube, position in start.items():
        assert np.linalg.norm(data.body(cube).xpos - position) < 0.015, cube
        assert data.body(cube).xmat.reshape(3, 3)[2, 2] > 0.99  # level: set down, not dropped


def test_a_cube_wider_than_the_open_gripper_is_not_picked(tmp_path):
    from prsc.runner.pick import pick

    spec = _spec(tmp_path, ARMS["franka_urdf"], "WideCube", _tcp("franka_urdf"))
    scene, model, data = readback.scene_at_home(_compiled(tmp_path, spec), 0)
    record = pick(scene, model, data)
    assert record["outcome"] in {"missed", "dropped"}, record


def test_an_arm_without_a_gripper_is_refused_by_name(tmp_path):
    from prsc.runner.pick import pick
    from prsc.errors import PrscError

    scene, model, data = readback.scene_at_home(_compiled(tmp_path, _spec(tmp_path, 'model: "xarm/xarm6_robot.urdf"')), 0)
    with pytest.raises(PrscError, match="arm has no gripper for pick: no actuator drives a joint off the chain"):
        pick(scene, model, data)

