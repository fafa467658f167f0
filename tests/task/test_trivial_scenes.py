"""A scene whose goal already holds is reported trivial, by `compile --settle-check` and by a run."""

from __future__ import annotations

import prsc
from prsc.runner.settle_check import report_lines, settle_scene
from prsc.scenario import mjcf_text

SPEC = '''from tabletop import *
table = Table on Vector3D(0, 0, 0), with width 1.0, with length 0.8, with height 0.8
tray = Tray completely on table, right of (top table) by 0.1
cube = Cube completely on {where}
goal cube in tray and cube at rest
'''


def _settled(tmp_path, where: str):
    path = tmp_path / f"{where}.prs"
    path.write_text(SPEC.format(where=where))
    scene = prsc.load(path).scene(0, 0)
    mjcf = tmp_path / f"{where}.xml"
    mjcf.write_text(mjcf_text(scene))
    return settle_scene(scene, mjcf)


def test_settle_check_reports_a_goal_that_holds_at_the_start(tmp_path):
    inside, outside = _settled(tmp_path, "tray"), _settled(tmp_path, "table")
    assert inside.trivial is True and outside.trivial is False
    lines = report_lines([inside, outside])
    assert "trivial" in lines[0] and "trivial" not in lines[1]
    assert lines[-1] == "task: the goal already holds at the start of 1 of 2 scenes (trivial episodes)"
