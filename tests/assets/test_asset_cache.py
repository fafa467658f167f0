"""Caches of converted assets keyed by every file they read (prsc/user_assets/asset_cache.py,
docs/assets.md "Caches"): the same robot in another folder after the first is gone, a mesh
edited under an unchanged URDF, and cache entries partly deleted, as a user's CI or lab
moves and edits robot descriptions. Each compile is a fresh `prsc` process, as a user runs it."""

from __future__ import annotations

import os
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
    arm = XArm on (top back table).position + Vector3D(0, 0.2, 0)
    ''')


def _compile(spec: Path, folder: Path, out: Path, build: Path, targets: str = "json,mjcf,urdf",
             scale: str | None = None) -> subprocess.CompletedProcess:
    env = dict(os.environ, PRSC_BUILD_DIR=str(build))
    return subprocess.run([sys.executable, "-m", "prsc.cli", "compile", str(spec), "--target", targets, "-n", "1",
                           "-I", str(folder), "-o", str(out)], capture_output=True, text=True, env=env, timeout=300)


def _robot_copy(into: Path) -> Path:
    shutil.copytree(XARM, into / "xarm", ignore=shutil.ignore_patterns("*gripper*", "link*.urdf", "base*.urdf"))
    return into


def _spec(tmp_path: Path, text: str = SPEC) -> Path:
    spec = tmp_path / "arm.prs"
    spec.write_text(text)
    return spec


def _build_texts(build: Path) -> str:
    return "\n".join(p.read_text(errors="replace") for p in build.rglob("*") if p.is_file() and p.suffix in (".urdf", ".xml"))


@pytest.mark.parametrize("scale", [None, "1.5"])
def test_robot_folder_deleted_then_compiled_from_another(tmp_path, scale):
    """Compiled from one folder, that folder deleted, then from a copy elsewhere: it works the
    first time, and no file in the build folder names the first folder (with `scale`, the
    scaled copy too)."""
    text = SPEC if scale is None else SPEC.replace("(0, 0.2, 0)", f"(0, 0.2, 0), with scale {scale}")
    spec, build = _spec(tmp_path, text), tmp_path / "build"
    first = _robot_copy(tmp_path / "first")
    done = _compile(spec, first, tmp_path / "out1", build)
    assert done.returncode == 0, done.stderr
    shutil.rmtree(first)
    second = _robot_copy(tmp_path / "second")
    done = _compile(spec, second, tmp_path / "out2", build)
    assert done.returncode == 0, done.stderr
    assert str(first) not in _build_texts(build)
    urdf = next((tmp_path / "out2" / "arm" / "urdf" / "00000").glob("*.urdf"), None)
    assert urdf is not None and str(first) not in urdf.read_text()


def test_edited_mesh_under_unchanged_urdf_reaches_the_next_compile(tmp_path):
    """A mesh replaced under an unchanged URDF: the next compile's MJCF and URDF name the new
    mesh's content, and the cached URDF of the robot is a new entry."""
    spec, build, folder = _spec(tmp_path), tmp_path / "build", _robot_copy(tmp_path / "robot")
    done = _compile(spec, folder, tmp_path / "before", build)
    assert done.returncode == 0, done.stderr
    mesh = folder / "xarm" / "xarm_description" / "meshes" / "xarm6" / "visual" / "link1.stl"
    new = (mesh.parent / "link2.stl").read_bytes()
    assert new != mesh.read_bytes()
    mesh.write_bytes(new)
    done = _compile(spec, folder, tmp_path / "after", build)
    assert done.returncode == 0, done.stderr
    for target, name in (("mjcf", "00000.xml"), ("urdf", "00000/arm.urdf")):
        out = tmp_path / "after" / "arm" / target / name
        text, base = out.read_text(), out.parent
        paths = [p for p in _mesh_paths(text) if p.endswith("/link1.stl")]
        assert paths, f"the {target} file names no link1.stl"
        assert all((base / p).read_bytes() == new for p in paths), f"the {target} file names the old link1.stl"
    assert len(list(build.glob("assets/xarm6_robot-*"))) == 2  # a new entry, the first left as it was


def _mesh_paths(text: str) -> list[str]:
    import re

    return re.findall(r'(?:file|filename)="([^"]+)"', text)


def test_cache_entry_missing_a_file_is_rebuilt(tmp_path):
    """A cache entry whose mesh copy was deleted (a partly cleaned build folder) is rebuilt, not trusted."""
    spec, build, folder = _spec(tmp_path), tmp_path / "build", _robot_copy(tmp_path / "robot")
    assert _compile(spec, folder, tmp_path / "one", build).returncode == 0
    copies = sorted(build.glob("assets/xarm6_robot-*/files/*/link1.stl"))
    assert copies
    for copy in copies:
        copy.unlink()
    done = _compile(spec, folder, tmp_path / "two", build)
    assert done.returncode == 0, done.stderr
    assert all(copy.is_file() for copy in copies)


def test_a_missing_input_is_named_as_the_input(tmp_path):
    """A mesh deleted under a URDF: the error names the mesh, never an output being written."""
    spec, build, folder = _spec(tmp_path), tmp_path / "build", _robot_copy(tmp_path / "robot")
    (folder / "xarm" / "xarm_description" / "meshes" / "xarm6" / "visual" / "link3.stl").unlink()
    done = _compile(spec, folder, tmp_path / "out", build)
    assert done.returncode == 2
    assert "link3.stl" in done.stderr and "cannot write" not in done.stderr, done.stderr
    assert "Traceback" not in done.stderr
