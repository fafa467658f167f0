"""`for i in range(...)`: parsing, unrolling, the names a loop gives, and its errors."""

from __future__ import annotations

import pytest

from prsc.cli import main
from prsc.errors import PrscError
from prsc.ir import compile_program
from prsc.ir.program import Program
from prsc.ir.loops import MAX_LOOP_ITERATIONS
from prsc.sampling import Sampler
from prsc.syntax import nodes
from prsc.syntax.parser import parse_source
from tests.sampling.scene_checks import check_scenes

H = "from tabletop import *\nt = Table on Vector3D(0, 0, 0)\n"


def compile_text(tmp_path, text: str) -> Program:
    path = tmp_path / "spec.prs"
    path.write_text(H + text)
    return compile_program(str(path))


def check_error(tmp_path, capsys, text: str) -> list[str]:
    """`prsc check` on a bad spec: exit 2, and the error's three lines (message, source, caret)."""
    path = tmp_path / "bad.prs"
    path.write_text(H + text)
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return [line.replace(str(path), "bad.prs") for line in err.splitlines()[:3]]


def test_a_loop_parses_to_its_variable_bounds_and_body():
    module = parse_source("for i in range(1, 4):\n    Cube\n    c = Cup on t\n    for j in range(2):\n        Ball\n",
                          "x.prs")
    (loop,) = module.statements
    assert isinstance(loop, nodes.ForLoop)
    assert (loop.var, loop.function, [a.value for a in loop.args]) == ("i", "range", [1.0, 4.0])
    assert [type(s).__name__ for s in loop.body] == ["ExprStmt", "ObjectStmt", "ForLoop"]
    assert (loop.var_span.line, loop.var_span.column) == (1, 5)


def test_named_objects_are_numbered_by_iteration_and_anonymous_ones_by_class(tmp_path):
    program = compile_text(tmp_path, "for i in range(3):\n"
                                     "    cup = Cup completely on t, with height 0.1 + 0.01 * i\n"
                                     "    Cube completely on t\n"
                                     "c = Cube at cup_2.position + Vector3D(0, 0, 0.2)\n")
    names = [o.name for o in program.objects]
    assert names == ["t", "cup_0", "cube_1", "cup_1", "cube_2", "cup_2", "cube_3", "c"]
    scene = Sampler(program, "exact").scene(0, 0)
    heights = [round(o["dimensions"][2], 9) for o in scene["objects"] if o["name"].startswith("cup_")]
    assert heights == [0.1, 0.11, 0.12]
    assert not any(o.anonymous for o in program.objects if o.name.startswith("cup_"))
    assert all(o.anonymous for o in program.objects if o.name.startswith("cube_"))


def test_nested_loops_name_objects_by_both_iterations_and_bounds_may_be_constants(tmp_path):
    program = compile_text(tmp_path, "rows = 2\n"
                                     "for i in range(rows):\n"
                                     "    for j in range(10, 16, 3):\n"
                                     "        box = Cube at Vector3D(i, j, 2)\n")
    names = [o.name for o in program.objects[1:]]
    assert names == ["box_0_0", "box_0_1", "box_1_0", "box_1_1"]
    xs = [o.specifiers[0].point.x.value for o in program.objects[1:]]
    ys = [o.specifiers[0].point.y.value for o in program.objects[1:]]
    assert (xs, ys) == ([0, 0, 1, 1], [10, 13, 10, 13])


def test_an_earlier_anonymous_object_does_not_take_a_loop_name(tmp_path):
    program = compile_text(tmp_path, "Cup completely on t\nfor i in range(3):\n    cup = Cup completely on t\n")
    assert [o.name for o in program.objects[1:]] == ["cup_3", "cup_0", "cup_1", "cup_2"]


def test_each_iteration_draws_afresh_and_requires_in_the_body_hold(tmp_path):
    program = compile_text(tmp_path, "for k in range(4):\n"
                                     "    part = Cube completely on t, with width (0.03, 0.08)\n"
                                     "    require part.x > -0.5 + 0.25 * k\n")
    widths = [dict(o.properties)["width"] for o in program.objects[1:]]
    assert len({w.draw_id for w in widths}) == 4
    assert len(program.requires) == 4
    scenes = list(Sampler(program, "exact").scenes(0, 30))
    report = check_scenes(program, scenes)
    assert not report, report
    for scene in scenes:
        xs = {o["name"]: o["position"][0] for o in scene["objects"]}
        assert all(xs[f"part_{k}"] > -0.5 + 0.25 * k for k in range(4))
    assert len({round(o["dimensions"][0], 6) for o in scenes[0]["objects"][1:]}) == 4


@pytest.mark.parametrize("text, expected", [
    ("for i in range(2.5):\n    Cube\n",
     ["bad.prs:3:16: error: range() needs whole numbers, not 2.5", "    for i in range(2.5):", " " * 19 + "^^^"]),
    ("for i in range((1, 3)):\n    Cube\n",
     ["bad.prs:3:16: error: range() needs constant whole numbers: a loop is unrolled before any scene is drawn, "
      "so its bounds cannot be random or read from objects"]),
    ("for i in range(1, 2, 0):\n    Cube\n", ["bad.prs:3:22: error: range() step must not be zero"]),
    ("for i in range():\n    Cube\n",
     ["bad.prs:3:10: error: range() takes 1 to 3 whole numbers (stop; start, stop; start, stop, step), got 0"]),
    (f"for i in range({MAX_LOOP_ITERATIONS + 1}):\n    Cube\n",
     [f"bad.prs:3:10: error: this loop runs {MAX_LOOP_ITERATIONS + 1} times; a spec unrolls at most "
      f"{MAX_LOOP_ITERATIONS} loop iterations in all", f"    for i in range({MAX_LOOP_ITERATIONS + 1}):",
      " " * 13 + "^" * 11]),
    ("for i in range(3):\n    for j in range(400):\n        Cube at Vector3D(i, j, 1)\n",
     ["bad.prs:4:14: error: this loop runs 400 times, which brings the spec's loops to 1203 iterations; "
      "a spec unrolls at most 1000 loop iterations in all"]),
    ("for i in items(3):\n    Cube\n",
     ["bad.prs:3:10: error: a loop runs over range(n) or range(start, stop), not items(...)"]),
    ("for i in range(3):\n    param x = 1\n",
     ["bad.prs:4:5: error: a param cannot be in a loop body: it is made once per spec, so write it before the loop"]),
    ("for Cube in range(2):\n    Ball\n",
     ["bad.prs:3:5: error: 'Cube' is already the class Cube: a loop variable needs a name of its own"]),
    ("for i in range(3):\n    i = 2\n", ["bad.prs:4:5: error: the loop variable 'i' cannot be bound in the loop body"]),
    ("for i in range(3):\nCube\n", ["bad.prs:4:1: error: expected an indented loop body (one statement per line)"]),
    ("for i in range(3):\n    cup = Cup\nc = Cube at cup.position\n",
     ["bad.prs:5:13: error: 'cup' names one object per iteration of the loop at line 3: after the loop, "
      "write one of cup_0 ... cup_2"]),
    ("for i in range(3):\n    Cube\nc = Cube at Vector3D(i, 0, 0)\n",
     ["bad.prs:5:22: error: 'i' is bound only inside the loop at line 3"]),
    ("for i in range(2):\n    cup = Cup\nfor i in range(2):\n    cup = Cup\n",
     ["bad.prs:6:5: error: 'cup_0' is already defined as the object cup_0 (a Cup)"]),
    ("  Cube\n", ["bad.prs:3:3: error: unexpected indentation (only a class or loop body is indented)"]),
])
def test_loop_errors_point_at_the_line_and_column(tmp_path, capsys, text, expected):
    assert check_error(tmp_path, capsys, text)[:len(expected)] == expected


def test_the_old_misleading_message_is_gone(tmp_path, capsys):
    lines = check_error(tmp_path, capsys, "for i in range(3) Cube\n")
    assert "unknown specifier" not in lines[0] and "expected ':'" in lines[0]


def test_a_loop_in_an_imported_file_exports_its_numbered_objects(tmp_path):
    (tmp_path / "lib.prs").write_text(H + "for i in range(2):\n    leg = Cube completely on t\n")
    main_spec = tmp_path / "main.prs"
    main_spec.write_text("from lib import *\nc = Cube on leg_1\n")
    program = compile_program(str(main_spec))
    assert [o.name for o in program.objects] == ["t", "leg_0", "leg_1", "c"]
    with pytest.raises(PrscError, match="'leg' names one object per iteration"):
        main_spec.write_text("from lib import *\nc = Cube on leg\n")
        compile_program(str(main_spec))


def test_after_nested_loops_a_body_name_lists_every_object(tmp_path, capsys):
    lines = check_error(tmp_path, capsys, "for i in range(2):\n    for j in range(3):\n        box = Cube\n"
                                          "c = Cube on box\n")
    assert lines[0] == ("bad.prs:6:13: error: 'box' names one object per iteration of the loop at line 3: "
                        "after the loop, write one of box_0_0 ... box_1_2")


def test_a_nested_loop_may_not_reuse_the_outer_variable(tmp_path, capsys):
    lines = check_error(tmp_path, capsys, "for i in range(2):\n    for i in range(3):\n        Cube\n")
    assert lines[0] == "bad.prs:4:9: error: the loop variable 'i' cannot be bound in the loop body"


def test_a_one_statement_body_may_follow_the_colon(tmp_path):
    program = compile_text(tmp_path, "for i in range(2): c = Cup completely on t, with height 0.1 + 0.01 * i\n"
                                     "for i in range(2): Cube completely on t\n")
    assert [o.name for o in program.objects[1:]] == ["c_0", "c_1", "cube_1", "cube_2"]
