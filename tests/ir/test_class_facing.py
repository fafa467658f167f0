"""`facing:` in a class body: a default orientation specifier that an object's own replaces."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from prsc.cli import main
from prsc.ir import compile_program, format_program
from prsc.ir import model as ir
from prsc.ir.program import Program
from prsc.sampling import Sampler
from prsc.syntax.parser import parse_source
from tests.sampling.scene_checks import check_scenes, quat_matrix

H = "from tabletop import *\nt = Table on Vector3D(0, 0, 0)\n"
MUG = "class Mug(Cup):\n    width: 0.08\n    facing: (0, 360 deg)\n"


def compile_text(tmp_path, text: str) -> Program:
    path = tmp_path / "spec.prs"
    path.write_text(H + text)
    return compile_program(str(path))


def orientation_specs(program: Program, name: str) -> list[ir.Specifier]:
    decl = next(o for o in program.objects if o.name == name)
    return [s for s in decl.specifiers if "orientation" in s.sets]


def yaw(obj: dict) -> float:
    """The yaw of a scene object about z, in [0, 2 pi): where its local +y points."""
    forward = quat_matrix(obj["quaternion"])[:, 1]
    return math.atan2(-forward[0], forward[1]) % (2 * math.pi)


def test_the_class_body_line_parses_as_a_specifier_default():
    module = parse_source("class Mug(Cup):\n    \"\"\"doc\"\"\"\n    width: 0.08\n    facing: (0, 360 deg)\n", "x.prs")
    (cls,) = module.statements
    assert [p.name for p in cls.properties] == ["width"]
    assert [(s.word, type(s.value).__name__) for s in cls.specifiers] == [("facing", "Pair")]


def test_every_object_gets_its_own_draw_and_its_own_specifier_wins(tmp_path):
    program = compile_text(tmp_path, MUG + "a = Mug completely on t\nb = Mug completely on t\n"
                                           "c = Mug completely on t, facing 90 deg\n"
                                           "d = Mug completely on t, facing toward a\n"
                                           "e = Mug at Vector3D(0, 0, 2), with orientation Vector3D(0.3, 0, 0)\n")
    (fa,), (fb,) = orientation_specs(program, "a"), orientation_specs(program, "b")
    assert isinstance(fa, ir.Facing) and fa.span.line == 5  # the class body's line
    assert fa.direction.draw_id != fb.direction.draw_id
    (fc,) = orientation_specs(program, "c")
    assert isinstance(fc, ir.Facing) and fc.direction.value == pytest.approx(math.pi / 2)
    assert [type(s).__name__ for s in orientation_specs(program, "d")] == ["FacingToward"]
    assert [type(s).__name__ for s in orientation_specs(program, "e")] == ["With"]
    (mug,) = [c for c in program.classes if c.name == "Mug"]
    assert [type(s).__name__ for s in mug.specifiers] == ["Facing"]
    assert "  Mug(Cup)  default: facing (0, 6.283185307179586)\n" in format_program(program)


def test_subclasses_inherit_the_default_and_may_replace_it(tmp_path):
    program = compile_text(tmp_path, MUG + "class Tumbler(Mug):\n    height: 0.1\n"
                                           "class Pointed(Mug):\n    facing: Vector3D(1, 0, 0)\n"
                                           "a = Tumbler completely on t\nb = Pointed completely on t\n")
    (fa,), (fb,) = orientation_specs(program, "a"), orientation_specs(program, "b")
    assert isinstance(fa.direction, ir.Distribution) and isinstance(fb.direction, ir.VectorExpr)


def test_the_default_yaw_is_uniform_and_the_test_sees_a_wrong_law(tmp_path):
    """Kolmogorov-Smirnov against U[0, 2 pi) over 300 scenes: passes for the class default,
    and rejects a half-turn default (the same test on the wrong law)."""
    def p_value(default: str) -> float:
        program = compile_text(tmp_path, f"class Mug(Cup):\n    facing: {default}\nm = Mug completely on t\n")
        scenes = list(Sampler(program, "exact").scenes(11, 300))
        report = check_scenes(program, scenes[:20])
        assert not report, report
        yaws = [yaw(next(o for o in s["objects"] if o["name"] == "m")) for s in scenes]
        return stats.kstest(np.array(yaws) / (2 * math.pi), "uniform").pvalue

    assert p_value("(0, 360 deg)") > 0.01
    assert p_value("(0, 180 deg)") < 1e-6


@pytest.mark.parametrize("body, expected", [
    ("    facing: 0\n    facing: 1\n", "bad.prs:5:5: error: duplicate `facing:` in class Mug"),
    ("    facing: \"north\"\n",
     "bad.prs:4:13: error: the default after `facing:` (a vector, or a yaw angle) must be a scalar or a vector, "
     "not a string"),
    ("    orientation: Vector3D(0, 0, 0)\n",
     "bad.prs:4:5: error: a class cannot give orientation a default: it is set by specifiers (at, on, in, "
     "facing, ...); for a default yaw write `facing: (0, 360 deg)`"),
])
def test_class_default_errors(tmp_path, capsys, body, expected):
    path = tmp_path / "bad.prs"
    path.write_text(H + "class Mug(Cup):\n" + body + "m = Mug\n")
    assert main(["check", str(path)]) == 2
    assert capsys.readouterr().err.splitlines()[0].replace(str(path), "bad.prs") == expected
