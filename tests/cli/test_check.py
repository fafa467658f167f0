"""`prsc check`: summaries, exit codes, error format, and no heavy imports."""

from __future__ import annotations

import subprocess

import pytest
import sys
from pathlib import Path

from prsc.cli import main
from tests.original import PRESENT, original_paths

REPO = Path(__file__).resolve().parents[2]


def test_originals_and_our_specs_check_clean(capsys):
    files = [str(p) for p in original_paths()] + sorted(str(p) for p in (REPO / "specs").glob("*.prs"))
    assert main(["check", *files]) == 0
    out = capsys.readouterr().out
    assert "table_cube.prs: ok, 7 objects (2 files)" in out
    assert "table_cube_naive.prs: ok, 7 objects, 14 requires (2 files)" in out
    assert "  tr_1: Tray -- completely on table; ahead of r1 by 0.1; left of (top table) by 0.2" in out
    assert PRESENT <= ("tableCube.prs: ok, 7 objects (2 files)" in out)


def test_summary_lists_specifiers_in_evaluation_order(tmp_path, capsys):
    spec = tmp_path / "s.prs"
    spec.write_text("from tabletop import *\nt = Table\nc = Cube on t, with width 0.1\n")
    assert main(["check", str(spec)]) == 0
    assert "  c: Cube -- with width 0.1; on t\n" in capsys.readouterr().out


def test_error_exit_code_and_format(tmp_path, capsys):
    spec = tmp_path / "bad.prs"
    spec.write_text("from tabletop import *\nc = Cube on 3.0\n")
    assert main(["check", str(spec)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err[0] == f"{spec}:2:13: error: `on` needs an object, a planar region or a point, not a scalar"
    assert err[1] == "    c = Cube on 3.0"
    assert err[2] == "    " + " " * 12 + "^^^"


def test_every_file_is_checked_and_any_error_fails(tmp_path, capsys):
    good, bad = tmp_path / "good.prs", tmp_path / "bad.prs"
    good.write_text("x = 1\n")
    bad.write_text("x = \n")
    assert main(["check", str(bad), str(good)]) == 2
    captured = capsys.readouterr()
    assert f"{good}: ok" in captured.out and f"{bad}:1:5: error" in captured.err


def test_include_directory(tmp_path, capsys):
    lib = tmp_path / "lib"
    lib.mkdir()
    (lib / "mine.prs").write_text("class Mine:\n    width: 0.5\n")
    spec = tmp_path / "s.prs"
    spec.write_text("from mine import *\nMine\n")
    assert main(["check", str(spec)]) == 2
    assert "import not found" in capsys.readouterr().err
    assert main(["check", "--include", str(lib), str(spec)]) == 0


def test_missing_file_and_directory(tmp_path, capsys):
    assert main(["check", str(tmp_path / "nope.prs"), str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "cannot read" in err and "is a directory" in err


def test_check_does_not_import_simulators():
    """check compiles as far as compile does before sampling (numpy, scipy), but loads no simulator
    for a spec without file assets (an arm, the library Panda too, is read from its file with
    MuJoCo: its box is the file's at home, docs/assets.md)."""
    code = ("import sys; from prsc.cli import main; rc = main(['check', '-q', 'specs/bin_ten_parts.prs']);"
            "heavy = [m for m in ('mujoco', 'pxr', 'pybullet', 'trimesh') if m in sys.modules];"
            "print(rc, heavy)")
    result = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "0 []"


NOT_A_CONTAINER = """from tabletop import *
table = Table on Vector3D(0, 0, 0)
block = Cube completely on table
c = Cube completely in block
"""
UNREADABLE_MESH = """class Thing(Object):
    mesh: "notamesh.obj"
a = Thing at Vector3D(0, 1, 1)
"""
LONG_NAME = "x" * 300 + " = Object at Vector3D(0, 1, 1)\n"


@pytest.mark.parametrize("source, line, col, words", [
    (NOT_A_CONTAINER, 4, 10, "needs a container"),
    (UNREADABLE_MESH, 2, 11, "notamesh.obj"),
    (LONG_NAME, 1, 1, "file systems allow 255"),
], ids=["not-a-container", "unreadable-mesh", "name-too-long"])
def test_check_finds_what_compile_finds_at_the_line_of_the_cause(tmp_path, capsys, source, line, col, words):
    """Issue 23: each of these passed `check` and then failed `compile`; now both say the same, at the same line."""
    (tmp_path / "notamesh.obj").write_text("not a mesh\n")
    spec = tmp_path / "s.prs"
    spec.write_text(source)
    assert main(["check", "-q", str(spec)]) == 2
    checked = capsys.readouterr().err
    assert checked.startswith(f"{spec}:{line}:{col}: error: ") and words in checked and "^" in checked
    out = tmp_path / "out"
    assert main(["compile", str(spec), "--target", "json,mjcf,urdf", "-o", str(out)]) == 2
    assert capsys.readouterr().err.splitlines()[0] == checked.splitlines()[0]
    assert not out.exists()

