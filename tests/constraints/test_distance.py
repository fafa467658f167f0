"""`distance from X to Y`: parsing, what it measures, how a require on it is enforced, errors."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from prsc.cli import main
from prsc.constraints import lower_program
from prsc.ir import compile_program
from prsc.ir import model as ir
from prsc.sampling import Sampler
from prsc.syntax import nodes
from prsc.syntax.parser import parse_source
from tests.sampling.scene_checks import check_scene, check_scenes

H = "from tabletop import *\nt = Table on Vector3D(0, 0, 0)\n"


def compile_text(tmp_path, text: str) -> ir.Program:
    path = tmp_path / "spec.prs"
    path.write_text(H + text)
    return compile_program(str(path))


def positions(scene: dict) -> dict[str, np.ndarray]:
    return {o["name"]: np.array(o["position"]) for o in scene["objects"]}


@pytest.mark.parametrize("text", ["require (distance from a to b) > 0.1\n", "require distance from a to b > 0.1\n"])
def test_distance_parses_as_an_operand_with_or_without_brackets(text):
    (req,) = parse_source(text, "x.prs").statements
    assert isinstance(req.condition, nodes.Compare)
    left = req.condition.left
    assert isinstance(left, nodes.Distance)
    assert (left.source.id, left.target.id) == ("a", "b")


def test_distance_takes_face_points_and_vectors_and_joins_arithmetic():
    """Its operands are single terms (a name, a face point, a call): `+ 1` applies to the distance."""
    (stmt,) = parse_source("x = 2 * distance from top a to Vector3D(0, 0, 1) + 1\n", "x.prs").statements
    assert isinstance(stmt.value, nodes.BinOp) and stmt.value.op == "+"
    product = stmt.value.left
    distance = product.right
    assert isinstance(distance, nodes.Distance)
    assert isinstance(distance.source, nodes.FacePoint) and isinstance(distance.target, nodes.Call)


def test_distance_measures_between_centres(tmp_path):
    program = compile_text(tmp_path, "a = Cube at Vector3D(0, 0, 1)\nb = Cube at Vector3D(0.3, 0.4, 1)\n"
                                     "d = distance from a to b\ne = distance from top a to Vector3D(0, 0, 2)\n"
                                     "require d == 0.5\nrequire e > 0.97 and e < 0.99\n")
    variables = {v.name: v.value for v in program.variables}
    assert isinstance(variables["d"], ir.Distance) and variables["d"].type == ir.Type.SCALAR
    scene = Sampler(program, "exact").scene(0, 0)  # the requires hold, or sampling would fail
    report = check_scene(program, scene)
    assert not report and report.checked > 0, report


def test_a_distance_require_is_checked_by_rejection_and_holds_in_every_scene(tmp_path):
    program = compile_text(tmp_path, "a = Cube completely on t\nb = Cube completely on t\n"
                                     "require (distance from a to b) < 0.4\n"
                                     "require (distance from a to b) > 0.2\n")
    cprog = lower_program(program)
    plan = next(p for p in cprog.objects if p.name == "b")
    assert len(plan.checks) == 2  # the Euclidean distance is not linear: no rows of its own
    scenes = list(Sampler(program, "exact").scenes(3, 100))
    gaps = [float(np.linalg.norm(positions(s)["a"] - positions(s)["b"])) for s in scenes]
    assert all(0.2 < g < 0.4 for g in gaps)
    assert min(gaps) < 0.23 and max(gaps) > 0.37  # the whole annulus, not a corner of it
    report = check_scenes(program, scenes)
    assert not report, report
    # The independent checker catches a scene that breaks the require.
    bad = copy.deepcopy(scenes[0])
    b = next(o for o in bad["objects"] if o["name"] == "b")
    a = next(o for o in bad["objects"] if o["name"] == "a")
    b["position"] = [a["position"][0] + 0.5, a["position"][1], a["position"][2] + 1.0]
    assert any("require at line 5" in problem for problem in check_scene(program, bad))


@pytest.mark.parametrize("text, expected", [
    ("a = Cube\nx = distance from 3 to a\n",
     "bad.prs:4:19: error: the point after `distance from` must be an object, an oriented point or a vector, "
     "not a scalar"),
    ("a = Cube\nx = distance from a to \"b\"\n",
     "bad.prs:4:24: error: the point after `distance from ... to` must be an object, an oriented point or a "
     "vector, not a string"),
    ("a = Cube\nx = distance a to a\n", "bad.prs:4:14: error: unexpected name 'a'; expected 'from'"),
])
def test_distance_errors_point_at_the_operand(tmp_path, capsys, text, expected):
    path = tmp_path / "bad.prs"
    path.write_text(H + text)
    assert main(["check", str(path)]) == 2
    assert capsys.readouterr().err.splitlines()[0].replace(str(path), "bad.prs") == expected
