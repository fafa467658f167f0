"""`prsc explain --stage syntax|ir|constraints|scene`: every compiler stage of specs/table_cube.prs."""

from __future__ import annotations

import json
from pathlib import Path

from prsc.cli import main

REPO = Path(__file__).resolve().parents[2]
TABLE_CUBE = str(REPO / "specs" / "table_cube.prs")


def _explain(capsys, *options: str) -> str:
    assert main(["explain", TABLE_CUBE, *options]) == 0
    return capsys.readouterr().out


def test_syntax_stage_is_the_ast_with_positions(capsys):
    lines = _explain(capsys, "--stage", "syntax").splitlines()
    assert lines[0] == f"Module 1:1 path={TABLE_CUBE!r}"
    assert "    - ImportFrom 8:1 module='tabletop'" in lines  # not followed: the syntax of one file
    start = lines.index("    - ObjectStmt 14:1 name='tr_1' class_name='Tray'")
    assert lines[start + 1 : start + 12] == [
        "      specifiers:",
        "        - OnSpec 14:13 completely=True",
        "          target: Name 14:27 id='table'",
        "        - DirectionSpec 15:5 relation='ahead'",
        "          target: Name 15:14 id='r1'",
        "          by: Number 15:20 value=0.1",
        "        - DirectionSpec 16:5 relation='left'",
        "          target: FacePoint 16:13 words=('top',) words_closed=True",
        "            target: Name 16:18 id='table'",
        "          by: Number 16:28 value=0.2",
        "    - ObjectStmt 17:1 name='tr_2' class_name='Tray'",
    ]


def test_syntax_stage_reports_a_syntax_error(tmp_path, capsys):
    bad = tmp_path / "bad.prs"
    bad.write_text("x = \n")
    assert main(["explain", str(bad), "--stage", "syntax"]) == 2
    assert capsys.readouterr().err.startswith(f"{bad}:1:5: error")


def test_ir_stage_is_the_typed_program(capsys):
    text = _explain(capsys, "--stage", "ir")
    assert text.startswith(f"program {TABLE_CUBE}\n  imports: ") and "tabletop.prs" in text.splitlines()[1]
    assert "objects (7), in evaluation order:" in text
    assert "  tr_1: Tray  [line 14]" in text
    assert "1. completely on table" in text and "ahead of r1 by 0.1" in text


def test_constraints_stage_is_the_default(capsys):
    text = _explain(capsys)
    assert text == _explain(capsys, "--stage", "constraints")
    assert text.startswith(f"spec: {TABLE_CUBE}\nevaluation order: table, r1, r2, tr_1, tr_2, c1, camera\n"
                           "path: batched (no two objects interact and every value vectorises)\n")
    assert f"tr_1 (Tray) declared at {TABLE_CUBE}:14" in text


def test_scene_stage_is_the_sampled_scene_indented(capsys):
    text = _explain(capsys, "--stage", "scene", "--seed", "3", "--index", "2")
    assert text.startswith("{\n  ") and text.endswith("}\n")
    assert main(["sample", TABLE_CUBE, "--seed", "3", "--start", "2"]) == 0
    [line] = capsys.readouterr().out.splitlines()
    assert json.loads(text) == json.loads(line)
    assert json.loads(text)["index"] == 2
