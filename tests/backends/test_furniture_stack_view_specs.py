"""The example specs of support surfaces, stacks and visibility: every format, at rest in MuJoCo."""

from __future__ import annotations

from pathlib import Path

import pytest

from prsc.backends import TARGETS
from prsc.cli import main
from prsc.ir import compile_program
from prsc.sampling import Sampler
from tests.sampling.scene_checks import check_scenes

SPECS = Path(__file__).resolve().parents[2] / "specs"


@pytest.mark.parametrize("name", ["kitchen_shelf", "stack_and_cube", "camera_view"])
def test_the_spec_compiles_to_every_format_and_its_scenes_are_at_rest(tmp_path, capsys, name):
    spec = SPECS / f"{name}.prs"
    targets = ",".join(TARGETS)
    code = main(["compile", str(spec), "-t", targets, "-n", "10", "-o", str(tmp_path), "--settle-check"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert "settle check: 10 of 10 scenes at rest" in out
    root = tmp_path / name
    for target in TARGETS:
        assert len(list((root / target).iterdir())) == 10, target
    program = compile_program(str(spec), (str(SPECS),))
    sampler = Sampler(program, "exact")
    report = check_scenes(program, [sampler.scene(0, i) for i in range(10)])  # the same scenes, checked
    assert not report and report.checked > 0, report
