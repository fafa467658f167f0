"""Task statements in the language: what they compile to, and each mistake an error at its line."""

from __future__ import annotations

import pytest

from prsc.cli import main
from prsc.errors import PrscError
from prsc.ir import compile_program

SCENE = '''from tabletop import *
table = Table on Vector3D(0, 0, 0), with width 1.0, with length 0.8, with height 0.8
tray = Tray completely on table, right of (top table) by 0.1
cube = Cube completely on table, left of (top table) by 0.1
arm = Robot on (top back table).position
cam = Camera at Vector3D(0, 0, 2), facing Vector3D(0, 0, -1)
goal = 3
record = goal + 1
'''


def _compile(tmp_path, task: str):
    path = tmp_path / "spec.prs"
    path.write_text(SCENE + task)
    return compile_program(str(path))


def test_every_statement_compiles_and_task_words_stay_names_elsewhere(tmp_path):
    program = _compile(tmp_path, '''goal cube completely in tray and cube at rest and cube upright for 1 seconds
goal not (arm touches cube) and cube left of tray by 0.01 and cube visible from cam
fail "dropped" when cube.z < table.z + table.height / 2 - 0.02 or cube.speed > 3
fail "held" when arm holds cube
terminate after 20 seconds
record initial cube.position as start
record final distance from cube to tray as gap
record cube above table by 0 as up
''')
    task = program.task
    assert [g.hold for g in task.goals] == [1.0, 0.5]
    assert [f.label for f in task.failures] == ["dropped", "held"] and task.time_limit == 20.0
    assert [(r.name, r.when) for r in task.records] == [("start", "initial"), ("gap", "final"), ("up", "step")]
    assert {v.name for v in program.variables} >= {"goal", "record"}  # `goal = 3` is still a variable


@pytest.mark.parametrize("task, line, column, message", [
    ("goal cube in bowl", 9, 14, "unknown object or class 'bowl'"),
    ("goal cube inside tray", 9, 11, "unexpected name 'inside'"),
    ("goal cube in cam", 9, 14, "cam is a camera"),
    ("goal cam touches cube", 9, 6, "cam is a camera"),
    ("goal cube visible from table", 9, 24, "needs a camera"),
    ("goal cube in Cuboid(Vector3D(0, 0, 1), Vector3D(0, 0, 0), 1, 1, 1)", 9, 14, "between objects"),
    ("goal cube in tray for 1", 9, 24, "a time is written `T seconds`"),
    ("goal cube in tray for 1 minutes", 9, 25, "unexpected name 'minutes'"),
    ("goal cube in tray for -1 seconds", 9, 23, "must be >= 0"),
    ("terminate after 0 seconds", 9, 17, "must be positive"),
    ('fail "a" when cube.z < 0\nfail "a" when cube.z > 2', 10, 6, 'label "a" is used twice'),
    ("goal cube.z", 9, 6, "expected a condition"),
    ("goal cube.mass > 1", 9, 11, "a task reads an object's"),
    ("goal cube in tray and cube.z", 9, 23, "expected a condition"),
])
def test_a_mistake_is_an_error_at_its_place(tmp_path, task, line, column, message):
    with pytest.raises(PrscError) as caught:
        _compile(tmp_path, task + "\n")
    error = caught.value
    assert message in error.message
    assert (error.span.line, error.span.column) == (line, column), error.message


def test_prsc_check_reports_the_task_and_its_errors_with_a_caret(tmp_path, capsys):
    path = tmp_path / "spec.prs"
    path.write_text(SCENE + "goal cube in bowl\n")
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"{path}:9:14: error: unknown object or class 'bowl'" in err and "^^^^" in err
    path.write_text(SCENE + "goal cube in tray for 2 seconds\n")
    assert main(["check", str(path)]) == 0
    assert "goal cube in tray for 2 seconds" in capsys.readouterr().out


def test_the_examples_of_docs_tasks_compile(tmp_path):
    import re
    from pathlib import Path

    text = (Path(__file__).parents[2] / "docs" / "tasks.md").read_text()
    spec = re.search(r"```prs\n(.*?)```", text, re.S).group(1)
    path = tmp_path / "example.prs"
    path.write_text(spec)
    program = compile_program(str(path))
    assert len(program.task.goals) == 1 and len(program.task.failures) == 2 and program.task.time_limit == 20
    statements = re.findall(r"^\| `(?:goal|fail|terminate|record).*?` \| `([^`]*)` \|", text, re.M)
    assert len(statements) == 4
    scene = spec.split("\ngoal ")[0] + "\n"
    for statement in statements:
        path.write_text(scene + statement + "\n")
        assert compile_program(str(path)).task


def test_holds_on_a_robot_without_known_finger_links_is_an_error_at_its_subject(tmp_path):
    """`R holds A` reads two finger links of R's gripper: the library arm names its own; a robot from
    another file names none, so the statement is an error at its subject, not a failed episode."""
    import pybullet_data

    arm = f"{pybullet_data.getDataPath()}/xarm/xarm6_robot.urdf"
    path = tmp_path / "spec.prs"
    path.write_text(SCENE + f'arm2 = Robot on Vector3D(-0.3, -0.35, 0.8), with model "{arm}"\n'
                    'fail "held" when arm holds cube\ngoal arm2 holds cube\n')
    with pytest.raises(PrscError) as caught:
        compile_program(str(path))
    error = caught.value
    assert (error.span.line, error.span.column) == (11, 6)
    assert "two finger links of arm2's gripper" in error.message and "names none" in error.message
