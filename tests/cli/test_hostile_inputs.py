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
