"""Caches of converted assets keyed by every file they read (prsc/user_assets/asset_cache.py,
docs/assets.md "Caches"): the same robot in another folder after the first is gone, a mesh
edited under an unchanged URDF, and cache entries partly deleted, as a user's CI or lab
moves and edits robot descriptions. Each compile is a fresh `prsc` process, as a user runs it."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

pybullet_data = pytest.importorskip("pybullet_data")
XARM = Path(pybullet_data.getDataPath()) / "xarm"
SPEC = textwrap.dedent('''\
    from tabletop import *

    class XArm(Robot):
        model: "xarm/xarm6_robot.urdf"

    table = Table on Vector3D(0, 0, 0), with width 1.2, with length 0.8, with height 0.75
    arm = XArm on (top back table).position + Vector3D(-0.3, 0.2, 0)
    big = XArm on (top back table).position + Vector3D(0.3, 0.2, 0), with scale 1.2
    ''')


def _compile(spec: Path, folder: Path, out: Path, build: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PRSC_BUILD_DIR=str(build))
    return subprocess.run([sys.executable, "-m", "prsc.cli", "compile", str(spec), "--target", "json,mjcf,urdf", "-n", "1",
                           "-I", str(folder), "-o", str(out)], capture_output=True, text=True, env=env, timeout=300)


def _robot_copy(into: Path) -> Path:
    shutil.copytree(XARM, into / "xarm", ignore=shutil.ignore_patterns("*gripper*", "link*.urdf", "base*.urdf"))
    return into


def _spec(tmp_path: Path) -> Path:
    spec = tmp_path / "arm.prs"
    spec.write_text(SPEC)
    return spec


def _build_texts(build: Path) -> str:
    return "\n".join(p.read_text(errors="replace") for p in build.rglob("*") if p.is_file() and p.suffix in (".urdf", ".xml"))


def _mesh_paths(text: str) -> list[str]:
    return re.findall(r'(?:file|filename)="([^"]+)"', text)


def test_robot_folder_deleted_then_compiled_from_another(tmp_path):
    """One robot (unscaled, and scaled: a copy in the build folder) as a user's CI meets it:
    compiled from one folder, that folder deleted and the cache cleaned in part, then compiled
    from a copy elsewhere: it works the first time, the cache's entries are rebuilt, not
    trusted, and no file in the build folder names the first folder."""
    spec, build = _spec(tmp_path), tmp_path / "build"
    first = _robot_copy(tmp_path / "first")
    done = _compile(spec, first, tmp_path / "out1", build)
    assert done.returncode == 0, done.stderr
    shutil.rmtree(first)
    copies = sorted(build.glob("**/files/*/link1.stl"))  # in the converted URDF's entry and the scaled copy's
    for copy in copies:
        copy.unlink()
    second = _robot_copy(tmp_path / "second")
    done = _compile(spec, second, tmp_path / "out2", build)
    assert done.returncode == 0, done.stderr
    assert str(first) not in _build_texts(build)
    assert str(first) not in (tmp_path / "out2" / "arm" / "urdf" / "00000" / "arm.urdf").read_text()
    assert len(copies) >= 2 and all(copy.is_file() for copy in copies)


def test_a_mesh_edited_under_an_unchanged_urdf_reaches_the_next_compile(tmp_path):
    """The robot compiled, then copied (a branch, a colleague's checkout) and a mesh replaced in
    the copy under its unchanged URDF: compiled from the copy, the MJCF and URDF (of the robot
    and of its scaled copy) carry the new mesh, from new cache entries; the first folder's
    entries stay as they were."""
    spec, build, first = _spec(tmp_path), tmp_path / "build", _robot_copy(tmp_path / "first")
    done = _compile(spec, first, tmp_path / "out1", build)
    assert done.returncode == 0, done.stderr
    second = _robot_copy(tmp_path / "second")
    mesh = second / "xarm" / "xarm_description" / "meshes" / "xarm6" / "visual" / "link1.stl"
    new = (mesh.parent / "link2.stl").read_bytes()
    assert new != mesh.read_bytes()
    entries = set(build.glob("assets/xarm6_robot-*"))
    mesh.write_bytes(new)
    done = _compile(spec, second, tmp_path / "out2", build)
    assert done.returncode == 0, done.stderr
    for target, name in (("mjcf", "00000.xml"), ("urdf", "00000/arm.urdf"), ("urdf", "00000/big.urdf")):
        out = tmp_path / "out2" / "arm" / target / name
        paths = [p for p in _mesh_paths(out.read_text()) if p.endswith("/link1.stl")]
        assert paths, f"{name} names no link1.stl"
        assert all((out.parent / p).read_bytes() == new for p in paths), f"{name} names the old link1.stl"
    assert set(build.glob("assets/xarm6_robot-*")) > entries  # new entries beside the first ones


def test_a_missing_input_is_named_as_the_input(tmp_path):
    """A mesh deleted under a URDF: the error names the mesh, never an output being written."""
    spec, build, folder = _spec(tmp_path), tmp_path / "build", _robot_copy(tmp_path / "robot")
    (folder / "xarm" / "xarm_description" / "meshes" / "xarm6" / "visual" / "link3.stl").unlink()
    done = _compile(spec, folder, tmp_path / "out", build)
    assert done.returncode == 2
    assert "link3.stl" in done.stderr and "cannot write" not in done.stderr, done.stderr
    assert "Traceback" not in done.stderr
