"""Inputs from the hostile campaign of issue 12 (items 5, 6, 7, 9): each is an error at its
place, exit code 2, never a crash, a hang or a leak of a file's contents."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from prsc.cli import main
from tests.backends.scenes import obj, scene

REPO = Path(__file__).resolve().parents[2]


def _error(capsys) -> str:
    err = capsys.readouterr().err
    assert "Traceback" not in err and "internal error" not in err
    return err


@pytest.mark.parametrize("size, message", [
    (1e-300, "width is 1e-300 m, outside what a simulator can represent (1e-06 to 1e+06 m)"),
    (1e300, "width is 1e+300 m, outside what a simulator can represent (1e-06 to 1e+06 m)"),
])
def test_sizes_a_simulator_cannot_hold_in_scene_json(tmp_path, capsys, size, message):
    source = tmp_path / "s.jsonl"
    source.write_text(json.dumps(scene([obj("speck", "Object", (0, 0, 1), (size, 0.1, 0.1))])) + "\n")
    assert main(["compile", str(source), "--target", "mjcf,usd", "-o", str(tmp_path / "o")]) == 2
    assert _error(capsys) == (f"{source}:1:1: error: object 'speck'.dimensions: {message}\n"
                              f"    {source.read_text().splitlines()[0][:160]}\n    ^\n")
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("value, where", [("0", "0"), ("-1", "-1"), ("1e-300", "1e-300"), ("1e300", "1e300")])
def test_check_names_the_line_of_a_size_a_simulator_cannot_hold(tmp_path, capsys, value, where):
    """Item 6: `with width 0` is an error of `check`, at the value."""
    spec = tmp_path / "w.prs"
    spec.write_text(f"a = Object at Vector3D(0, 0, 1)\nb = Object at Vector3D(0, 0, 3),\n    with width {value}\n")
    assert main(["check", str(spec)]) == 2
    err = _error(capsys)
    column = 16
    assert err.startswith(f"{spec}:3:{column}: error: width of b ")
    assert err.splitlines()[2] == "    " + " " * (column - 1) + "^" * len(where)


def test_a_random_size_out_of_range_is_reported_at_the_object(tmp_path, capsys):
    spec = tmp_path / "r.prs"
    spec.write_text("x = 1\nb = Object at Vector3D(0, 0, 1), with width (0, 1e-12)\n")
    assert main(["compile", str(spec), "-o", str(tmp_path / "o")]) == 2
    assert _error(capsys).startswith(f"{spec}:2:1: error: width of b is ")
    assert not (tmp_path / "o").exists()


def test_a_json_file_nested_100000_deep(tmp_path, capsys):
    source = tmp_path / "deep.json"
    source.write_text('{"format": "prsc-scene",\n "x": ' + "[" * 100000 + "]" * 100000 + "}")
    assert main(["compile", str(source), "-o", str(tmp_path / "o")]) == 2
    assert _error(capsys).startswith(f"{source}:2:106: error: JSON nested more than 100 levels deep\n")


@pytest.mark.parametrize("expression, column", [("- " * 10000 + "1", 403), ("not " * 10000 + "True", 801)])
def test_deep_nesting_is_reported_at_its_line(tmp_path, capsys, expression, column):
    """Item 6: nesting 10,000 deep is an error at the offending line, not line 1."""
    spec = tmp_path / "deep.prs"
    spec.write_text(f"a = 1\nb = 2\nx = {expression}\n")
    assert main(["check", str(spec)]) == 2
    assert _error(capsys).startswith(f"{spec}:3:{column}: error: this expression is nested too deeply")


def test_a_spec_over_the_size_limit_is_refused_before_parsing(tmp_path, capsys):
    """Item 7: one long sum of 300 KiB is refused at once (the documented 256 KiB limit)."""
    spec = tmp_path / "sum.prs"
    spec.write_text("x = " + "+".join(["1"] * 150_000) + "\n")
    assert main(["check", str(spec)]) == 2
    assert _error(capsys).startswith(f"{spec}:1:1: error: file too large (over 256 KiB; a spec may be at most 256 KiB)")


def test_a_fifo_spec_does_not_block_after_its_error(tmp_path):
    """Item 7: the caret line is not read again from a FIFO (that would wait for a writer forever)."""
    fifo = tmp_path / "spec.prs"
    os.mkfifo(fifo)
    run = subprocess.Popen([sys.executable, "-m", "prsc.cli", "check", str(fifo)], stderr=subprocess.PIPE,
                           text=True, cwd=REPO, env=dict(os.environ, PYTHONPATH=str(REPO)))
    writer = threading.Thread(target=lambda: fifo.write_text("a = Object at Vector3D(0, 0, 1)\nb = = 2\n"))
    writer.start()
    try:
        err = run.communicate(timeout=60)[1]
    finally:
        run.kill()
        writer.join(timeout=5)
    assert run.returncode == 2 and err.startswith(f"{fifo}:2:5: error: unexpected '='")


def _mesh_spec(folder: Path, mesh: str) -> Path:
    spec = folder / "m.prs"
    spec.write_text(f'a = Object at Vector3D(0, 0, 1),\n    with shape "mesh", with mesh "{mesh}"\n')
    return spec


def test_a_mesh_outside_the_spec_folder_needs_a_flag(tmp_path, capsys):
    """Item 9: an absolute or `..` mesh path is read only with --meshes-anywhere."""
    project, elsewhere = tmp_path / "project", tmp_path / "elsewhere"
    project.mkdir(), elsewhere.mkdir()
    import trimesh

    trimesh.creation.box().export(elsewhere / "box.stl")
    for mesh in (str(elsewhere / "box.stl"), "../elsewhere/box.stl"):
        spec = _mesh_spec(project, mesh)
        assert main(["check", str(spec)]) == 0
        capsys.readouterr()
        assert main(["compile", str(spec), "--target", "mjcf", "-o", str(tmp_path / "o")]) == 2
        assert _error(capsys).startswith(f"{spec}:1:1: error: object 'a': mesh file '{mesh}' is outside the spec's "
                                         "folder and the --include folders; pass --meshes-anywhere to read it\n")
        assert not (tmp_path / "o").exists()
    assert main(["compile", str(spec), "--target", "mjcf", "-o", str(tmp_path / "o"), "--meshes-anywhere"]) == 0
    # Found through --include, it needs no flag.
    spec = _mesh_spec(project, "box.stl")
    assert main(["compile", str(spec), "--target", "mjcf", "-o", str(tmp_path / "p"), "-I", str(elsewhere)]) == 0


def test_a_missing_mesh_is_an_error_of_check_at_its_line(tmp_path, capsys):
    spec = _mesh_spec(tmp_path, "nowhere.obj")
    assert main(["check", str(spec)]) == 2
    assert _error(capsys).startswith(f"{spec}:2:34: error: a: mesh file 'nowhere.obj' not found")


def test_an_unreadable_mesh_is_reported_at_the_object_without_its_contents(tmp_path, capsys):
    (tmp_path / "leak.xyz").write_text("hunter2-secret 1 2\n")
    spec = _mesh_spec(tmp_path, "leak.xyz")
    assert main(["compile", str(spec), "--target", "mjcf", "-o", str(tmp_path / "o")]) == 2
    err = _error(capsys)
    # Its sizes come from the mesh's bounds, so the front end reads it: the error is at the name.
    assert err.startswith(f"{spec}:2:34: error: a: cannot read mesh {tmp_path / 'leak.xyz'}: not a mesh file")
    assert "hunter2" not in err
    assert not (tmp_path / "o").exists()


# ------------------------------------------------------------------ the build folder between runs
# Issue 41: caches of a user's asset (its converted URDF, a scaled copy) moved, deleted or made
# read-only between runs, each run a fresh process as a user's. Root ignores chmod, so a
# read-only build folder is a process whose every write under it fails with EROFS.

THING = """<?xml version="1.0"?>
<robot name="thing">
  <link name="base"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><geometry><mesh filename="meshes/tet.obj" scale="0.2 0.2 0.2"/></geometry></visual>
    <collision><geometry><mesh filename="meshes/tet.obj" scale="0.2 0.2 0.2"/></geometry></collision></link>
  <link name="lid"><inertial><mass value="0.1"/><inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><origin xyz="0 0 0.2"/><geometry><box size="0.1 0.1 0.02"/></geometry></visual></link>
  <joint name="hinge" type="revolute"><parent link="base"/><child link="lid"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="1" effort="1" velocity="1"/></joint>
</robot>
"""
THING_SPEC = """class Thing(Object):
    model: "thing/thing.urdf"

t = Thing at Vector3D(0, 0, 0.5)
big = Thing at Vector3D(1, 0, 0.5), with scale 1.5
"""
READ_ONLY = """
import errno, os, sys
build = os.path.realpath(os.environ["PRSC_BUILD_DIR"])
def refused(path):
    return os.path.realpath(os.fspath(path)).startswith(build)
def wrap(call, writes):
    def wrapped(path, *args, **kwargs):
        if writes(args, kwargs) and refused(path):
            raise OSError(errno.EROFS, os.strerror(errno.EROFS), os.fspath(path))
        return call(path, *args, **kwargs)
    return wrapped
os.open = wrap(os.open, lambda a, k: (a[0] if a else k.get("flags", 0)) & (os.O_WRONLY | os.O_RDWR | os.O_CREAT))
os.mkdir = wrap(os.mkdir, lambda a, k: True)
os.replace = wrap(os.replace, lambda a, k: True)
os.rename = wrap(os.rename, lambda a, k: True)
os.unlink = wrap(os.unlink, lambda a, k: True)
from prsc.cli import main
sys.exit(main(sys.argv[1:]))
"""


def _thing_project(folder: Path) -> Path:
    (folder / "thing" / "meshes").mkdir(parents=True)
    (folder / "thing" / "thing.urdf").write_text(THING)
    (folder / "thing" / "meshes" / "tet.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    spec = folder / "things.prs"
    spec.write_text(THING_SPEC)
    return spec


def _compile_with_build(spec: Path, out: Path, build: Path, read_only: bool = False) -> subprocess.CompletedProcess:
    command = ["-c", READ_ONLY] if read_only else ["-m", "prsc.cli"]
    return subprocess.run([sys.executable, *command, "compile", str(spec), "--target", "json,mjcf,urdf", "-o", str(out)],
                          capture_output=True, text=True, env=dict(os.environ, PRSC_BUILD_DIR=str(build)), timeout=300)


def _files(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _written(out: Path) -> dict[str, bytes]:
    """The simulator files of an output folder (its JSON files name the spec's path, and scene JSON
    a scaled copy by its place in the build folder)."""
    return {name: data for name, data in _files(out).items() if not name.endswith(".json")}


def test_cached_assets_moved_deleted_and_read_only_between_runs(tmp_path):
    spec, build = _thing_project(tmp_path / "project"), tmp_path / "build"
    done = _compile_with_build(spec, tmp_path / "o1", build)
    assert done.returncode == 0, done.stderr
    cached = _files(build)
    assert any(name.endswith(".urdf") for name in cached) and str(tmp_path / "project") not in str(cached.values())

    # The build folder moved: every entry is used as it is (nothing rebuilt, nothing added).
    moved = tmp_path / "elsewhere" / "build"
    moved.parent.mkdir()
    build.rename(moved)
    done = _compile_with_build(spec, tmp_path / "o2", moved)
    assert done.returncode == 0, done.stderr
    assert _files(moved) == cached
    assert _written(tmp_path / "o2") == _written(tmp_path / "o1")

    # Read-only: a complete cache is read without a write; an empty one is a clear error.
    done = _compile_with_build(spec, tmp_path / "o3", moved, read_only=True)
    assert done.returncode == 0, done.stderr
    assert _written(tmp_path / "o3") == _written(tmp_path / "o1")
    empty = tmp_path / "empty-build"
    empty.mkdir()
    done = _compile_with_build(spec, tmp_path / "o4", empty, read_only=True)
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert f"cannot write the build folder {empty}" in done.stderr and "PRSC_BUILD_DIR" in done.stderr, done.stderr
    assert not (tmp_path / "o4").exists()

    # Files of the cache deleted (every other one): the entries are rebuilt, the output the same.
    for k, name in enumerate(sorted(cached)):
        if k % 2 == 0:
            (moved / name).unlink()
    # ... and the asset's own folder moved too.
    (tmp_path / "project").rename(tmp_path / "project2")
    done = _compile_with_build(tmp_path / "project2" / "things.prs", tmp_path / "o5", moved)
    assert done.returncode == 0, done.stderr
    assert _files(moved) == cached
    assert _written(tmp_path / "o5") == _written(tmp_path / "o1")
