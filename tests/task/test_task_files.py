"""The compiled task travels with the outputs: the scene JSON's "task" key and a bundle's task.json."""

from __future__ import annotations

import json
from pathlib import Path

from prsc.cli import main
from prsc.task.terms import Task

SPEC = Path(__file__).with_name("tray_task.prs")


def test_a_bundle_holds_the_scene_s_task_json(tmp_path):
    assert main(["compile", str(SPEC), "--target", "json,urdf", "-n", "1", "-o", str(tmp_path)]) == 0
    folder = tmp_path / "tray_task"
    scene = json.loads((folder / "json" / "00000.json").read_text())
    task = json.loads((folder / "urdf" / "00000" / "task.json").read_text())
    assert task == scene["task"]
    compiled = Task.from_json(task)
    assert Task.from_json(compiled.to_json()) == compiled  # plain data, both ways
    assert [o.name for o in compiled.objects] == ["table", "tray", "cube"] and compiled.object("tray").container
