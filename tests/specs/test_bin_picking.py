"""specs/bin_picking.prs, as a user runs it: every format, 10 scenes at rest in MuJoCo, and
every relation (the loop's objects, their class default yaws, the bin) checked independently."""

from __future__ import annotations

import json
import math
from pathlib import Path

from prsc.backends import TARGETS
from prsc.cli import main
from prsc.ir import compile_program
from prsc.ir import model as ir
from tests.sampling.scene_checks import check_scenes, quat_matrix

SPEC = Path(__file__).resolve().parents[2] / "specs" / "bin_picking.prs"
LOOP_OBJECTS = [f"{kind}_{k}" for k in range(4) for kind in ("part", "can")]


def test_the_loop_declares_eight_objects_with_class_default_yaws():
    program = compile_program(str(SPEC))
    declared = {o.name: o for o in program.objects}
    assert [o.name for o in program.objects if o.name in LOOP_OBJECTS] == LOOP_OBJECTS
    draws = set()
    for name in LOOP_OBJECTS:
        specs = declared[name].specifiers
        (facing,) = [s for s in specs if isinstance(s, ir.Facing)]
        draws.add(facing.direction.draw_id)
        assert any(isinstance(s, ir.On) and s.completely and s.target.name == "bin_1" for s in specs)
    assert len(draws) == 8  # one yaw drawn per object


def test_it_compiles_to_every_format_and_ten_scenes_settle(tmp_path, capsys):
    out = tmp_path / "out"
    targets = ",".join(TARGETS)
    assert main(["compile", str(SPEC), "-t", targets, "-n", "10", "-o", str(out), "--settle-check"]) == 0
    printed = capsys.readouterr().out
    assert "settle check: 10 of 10 scenes at rest (no free object moved more than 2 mm in 1 s)" in printed
    root = out / "bin_picking"
    manifest = json.loads((root / "manifest.json").read_text())
    assert [sorted(s["files"]) for s in manifest["scenes"]] == [sorted(TARGETS)] * 10
    for scene in manifest["scenes"]:
        assert all((root / path).exists() for path in scene["files"].values()), scene
    scenes = [json.loads(p.read_text()) for p in sorted((root / "json").iterdir())]
    program = compile_program(str(SPEC))
    report = check_scenes(program, scenes)
    assert not report, report
    yaws = set()
    for scene in scenes:
        for obj in scene["objects"]:
            if obj["name"] in LOOP_OBJECTS:
                forward = quat_matrix(obj["quaternion"])[:, 1]
                yaws.add(round(math.atan2(-forward[0], forward[1]), 6))
    assert len(yaws) == 80  # every object of every scene at its own yaw
