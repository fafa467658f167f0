"""`python -m prsc.runner.settle_report`: the demo's load-and-step check of a compiled scene."""

from __future__ import annotations

import json
from pathlib import Path

from prsc.runner.settle_report import main, settle
from prsc.cli import main as prsc_main

DATA = Path(__file__).resolve().parents[1] / "data"


def test_report_lists_every_object_and_the_cube_that_drops_into_the_tray(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the file must load from any working directory
    assert prsc_main(["compile", str(DATA / "table_cube_scene.json"), "--target", "mjcf", "-o", "out"]) == 0
    mjcf = next((tmp_path / "out").rglob("*.xml"))
    capsys.readouterr()
    assert main([str(mjcf), "--seconds", "0.5"]) == 0
    table = capsys.readouterr().out
    for name in ("table", "r1", "r2", "tr_1", "tr_2", "c1", "camera"):
        assert f"│ {name} " in table
    model, before, after = settle(mjcf, 0.5)
    cube = model.body("c1").id
    drop = before[cube][2] - after[cube][2]
    # The cube rests on the tray's rim plane (the box's top face) and falls onto its floor.
    assert 0.015 < drop < 0.03
    scene = json.loads((DATA / "table_cube_scene.json").read_text())
    fixed = [o["name"] for o in scene["objects"] if o["static"]]
    for name in fixed:
        assert abs(after[model.body(name).id] - before[model.body(name).id]).max() < 1e-9
