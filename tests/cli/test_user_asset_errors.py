"""A user's asset that cannot be used is an error at the line that names it, from `prsc
check` as from `prsc compile` (exit code 2, `file:line:col`, a caret, nothing written):
a missing or unparsable file, a `package://` that resolves nowhere, xacro left in a URDF, a joint the file does
not have or a value outside its limits, a size the file decides, `reachable by` on an
object that is not a robot and `with joint` on one without a file. The original model
library's `model_name: "Panda"` is a robot for `reachable by`."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ARM = """<mujoco model="two_link"><compiler angle="radian"/><worldbody><body name="base"><geom type="cylinder" size="0.05 0.05"/>
<body name="link1" pos="0 0 0.1"><joint name="shoulder" axis="0 1 0" range="-1.5 1.5"/>
<geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/></body></body></worldbody></mujoco>"""

HEAD = "from tabletop import *\nclass Arm(Robot):\n    pass\n"
CASES = {
    "missing file": ('arm = Arm at Vector3D(0, 0, 0.3), with model "missing.urdf"', 4, 46, "asset file 'missing.urdf' not found"),
    "unparsable URDF": ('arm = Arm at Vector3D(0, 0, 0.3), with model "broken.urdf"', 4, 46, "cannot read URDF broken.urdf"),
    "unresolved package": ('arm = Arm at Vector3D(0, 0, 0.3), with model "pkg.urdf"', 4, 46,
                           "'package://nowhere/m.obj' does not resolve"),
    "unknown joint": ('arm = Arm at Vector3D(0, 0, 0.3), with model "arm.xml", with joint "shouldr" 0.2', 4, 78,
                      "has no joint 'shouldr'; did you mean 'shoulder'?"),
    "value outside limits": ('arm = Arm at Vector3D(0, 0, 0.3), with model "arm.xml", with joint "shoulder" (0, 2)',
                             4, 79, "joint 'shoulder' value 0..2 rad is outside its limits [-1.5, 1.5] rad"),
    "size from the file": ('arm = Arm at Vector3D(0, 0, 0.3), with model "arm.xml", with height 0.3', 4, 69,
                           "the height of an asset from a file is the file's"),
    "reachable by a cube": ("b = Cube at Vector3D(0, 0, 0.02)\nc = Cube at Vector3D(0.3, 0, 0.02), reachable by b",
                            5, 37, "'reachable by' needs a robot"),
    "xacro left in a URDF": ('arm = Arm at Vector3D(0, 0, 0.3), with model "xacro.urdf"', 4, 46,
                             'xacro.urdf: line 3, <origin xyz="$(optenv IMU_XYZ 0.19 0 0.149)"> is a xacro expression'),
    "joint without a file": ('c = Cube at Vector3D(0.3, 0, 0.02), with joint "x" 1', 4, 52,
                             "`with joint` needs an object whose model is a URDF or MJCF file"),
}


def _prsc(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "prsc.cli", *args], capture_output=True, text=True, cwd=cwd, timeout=300)


@pytest.fixture()
def folder(tmp_path):
    (tmp_path / "arm.xml").write_text(ARM)
    (tmp_path / "broken.urdf").write_text("<robot name='x'><link name='a'>\n")
    (tmp_path / "pkg.urdf").write_text('<robot name="p"><link name="a"><visual><geometry>'
                                       '<mesh filename="package://nowhere/m.obj"/></geometry></visual></link></robot>\n')
    # husky.urdf's IMU, as pybullet ships it: MuJoCo only says "bad format in attribute 'xyz'".
    (tmp_path / "xacro.urdf").write_text('<robot name="x">\n<link name="a"/><link name="b"/>\n<joint name="j" type="fixed">'
                                         '<origin xyz="$(optenv IMU_XYZ 0.19 0 0.149)"/>\n<parent link="a"/><child link="b"/></joint></robot>\n')
    return tmp_path


@pytest.mark.parametrize("case", sorted(CASES))
def test_check_and_compile_report_it_at_its_line(folder, case):
    body, line, column, message = CASES[case]
    spec = folder / "s.prs"
    spec.write_text(HEAD + body + "\n")
    for command in (["check", "s.prs"], ["compile", "s.prs", "-n", "2", "--target", "mjcf", "-o", "out"]):
        done = _prsc(*command, cwd=folder)
        assert done.returncode == 2, (command, done.stderr)
        first = done.stderr.splitlines()[0]
        assert first.startswith(f"s.prs:{line}:{column}: error: ") and message in first, first
        assert "^" in done.stderr and "Traceback" not in done.stderr
    assert not (folder / "out").exists()


def test_the_original_model_name_panda_is_reachable_by(tmp_path):
    spec = tmp_path / "s.prs"
    spec.write_text("from tabletop import *\nclass Arm:\n    model_name: \"Panda\"\n    width: 0.14\n"
                    "    length: 0.22\n    height: 1.025562\n"
                    "table = Table on Vector3D(0, 0, 0), with width 1.8, with length 0.8, with height 0.8\n"
                    "r = Arm on (top back table).position, facing 0 deg\n"
                    "c = Cube completely on table, reachable by r\n")
    done = _prsc("sample", "s.prs", "-n", "3", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    import json

    for line in done.stdout.splitlines():
        objects = {o["name"]: o for o in json.loads(line)["objects"]}
        assert objects["r"]["model"] == "panda"
        # In the Panda's ring about its base: past its inner radius (0.21 m), within its outer one (0.81 m).
        offset = np.subtract(objects["c"]["position"], objects["r"]["position"])[:2]
        assert 0.21 < np.hypot(*offset) < 0.81
