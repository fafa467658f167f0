"""`distance from X to Y`: parsing, what it measures, how a require on it is enforced, errors."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from scipy import stats

from prsc.cli import main
from prsc.constraints import lower_program
from prsc.ir import compile_program
from prsc.ir import model as ir
from prsc.ir.program import Program
from prsc.sampling import Sampler
from prsc.syntax import nodes
from prsc.syntax.parser import parse_source
from tests.sampling.scene_checks import check_scene, check_scenes

H = "from tabletop import *\nt = Table on Vector3D(0, 0, 0)\n"


def compile_text(tmp_path, text: str) -> Program:
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


BALL = ("a = Cube at Vector3D(0.2, 0.1, 0.92)\nb = Cube completely on t\n"
        "require (distance from a to b) < 0.3\n")


@pytest.mark.parametrize("condition", ["(distance from a to b) < 0.3", "0.3 >= distance from b to a",
                                       "not (distance from a to b >= 0.3)", "b.z > 0 and distance from a to b < 0.3"])
def test_an_upper_bound_on_a_distance_also_gives_the_box_around_the_ball_as_rows(tmp_path, condition):
    program = compile_text(tmp_path, BALL.replace("(distance from a to b) < 0.3", condition))
    plan = next(p for p in lower_program(program).objects if p.name == "b")
    assert len(plan.checks) == 1  # the ball itself is still checked
    rows = plan.region.static_rows
    box = rows.A[rows.labels == plan.checks[0].label_id]
    bounds = rows.b[rows.labels == plan.checks[0].label_id]
    # |x - 0.2| <= 0.3, |y - 0.1| <= 0.3, |z - 0.92| <= 0.3 (a's centre is known before b)
    found = {(tuple(float(v) + 0.0 for v in row), round(float(bound), 9)) for row, bound in zip(box, bounds)}
    expected = {((1, 0, 0), 0.5), ((0, 1, 0), 0.4), ((0, 0, 1), 1.22),
                ((-1, 0, 0), 0.1), ((0, -1, 0), 0.2), ((0, 0, -1), -0.62)}
    linear = {((0, 0, -1), 0.0)} if "b.z > 0" in condition else set()  # the linear part: exact rows too
    assert found == expected | linear


def _uniform_on_the_ring(radii: np.ndarray) -> float:
    """A Kolmogorov-Smirnov p-value: are the radii those of points uniform on the ring
    0.06 m < r < 0.3 m (where the 8 cm square the collision rule keeps clear lies inside
    0.06 m)? Uniform over the area means r squared is uniform."""
    ring = radii[radii > 0.06]
    return stats.kstest((ring ** 2 - 0.06 ** 2) / (0.3 ** 2 - 0.06 ** 2), "uniform").pvalue


def test_the_box_keeps_the_law_uniform_on_the_ball_and_the_test_sees_a_wrong_law(tmp_path):
    program = compile_text(tmp_path, BALL)
    scenes = list(Sampler(program, "exact").scenes(17, 400))
    radii = np.array([np.hypot(*(positions(s)["b"][:2] - np.array([0.2, 0.1]))) for s in scenes])
    assert np.all(radii < 0.3)
    assert _uniform_on_the_ring(radii) > 0.001
    # The wrong law of a naive polar draw: the radius itself uniform (crowds the centre).
    wrong = np.random.default_rng(0).uniform(0.06, 0.3, size=400)
    assert _uniform_on_the_ring(wrong) < 1e-4


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
