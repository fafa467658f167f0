"""The example specs of docs/language.md's tasks, run as a user runs them: `prsc compile` in
a subprocess, to every format, 10 scenes each at rest in MuJoCo (no free object moving more
than 2 mm in 1 s), and every relation of every scene checked independently."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from prsc.backends import TARGETS
from prsc.ir import compile_program
from tests.sampling.scene_checks import check_scenes

REPO = Path(__file__).resolve().parents[2]
EXAMPLES = ["bin_picking", "kitchen_shelf", "stack_and_cube", "user_mesh", "camera_view"]


@pytest.mark.parametrize("name", EXAMPLES)
def test_the_example_compiles_to_every_format_and_ten_scenes_settle(tmp_path, name):
    run = subprocess.run([sys.executable, "-m", "prsc.cli", "compile", f"specs/{name}.prs", "--target", ",".join(TARGETS),
                          "-n", "10", "--seed", "0", "-o", str(tmp_path), "--settle-check"],
                         capture_output=True, text=True, cwd=REPO, timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "settle check: 10 of 10 scenes at rest (no free object moved more than 2 mm in 1 s)" in run.stdout
    root = tmp_path / name
    scenes = json.loads((root / "manifest.json").read_text())["scenes"]
    assert [sorted(s["files"]) for s in scenes] == [sorted(TARGETS)] * 10
    assert all((root / path).exists() for s in scenes for path in s["files"].values())
    program = compile_program(str(REPO / "specs" / f"{name}.prs"))
    report = check_scenes(program, [json.loads(p.read_text()) for p in sorted((root / "json").iterdir())])
    assert not report and report.checked > 0, report
