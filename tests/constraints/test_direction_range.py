"""`ahead of X by (low, high)` and its siblings: a gap in [low, high], two exact half-spaces;
a bare `by d` stays "at least d"."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from prsc.cli import main
from prsc.constraints.specifier_rows import DIRECTION_AXES, rows_direction
from prsc.constraints.support import Support
from prsc.ir import compile_program
from prsc.ir import model as ir
from prsc.ir.program import Program
from prsc.sampling import Sampler
from tests.sampling.scene_checks import check_scene, check_scenes

H = "from tabletop import *\nt = Table on Vector3D(0, 0, 0)\nr = Robot on (top back t).position\n"


def compile_text(tmp_path, text: str) -> Program:
    path = tmp_path / "spec.prs"
    path.write_text(H + text)
    return compile_program(str(path))


def gap(scene: dict, name: str, reference: str, relation: str) -> float:
    """The gap from the plane through the reference's centre to the object's nearest face
    (both unrotated here: the plane's normal is the world axis of the relation)."""
    objects = {o["name"]: o for o in scene["objects"]}
    n = DIRECTION_AXES[relation]
    obj, ref = objects[name], objects[reference]
    half = 0.5 * float(np.abs(n) @ np.array(obj["dimensions"]))
    return float(n @ (np.array(obj["position"]) - np.array(ref["position"]))) - half


def test_by_a_pair_is_a_least_and_a_greatest_gap_in_the_ir(tmp_path):
    program = compile_text(tmp_path, "c = Cube completely on t, ahead of r by (0.4, 0.6)\n"
                                     "d = Cube completely on t, ahead of r by Range(0.4, 0.6)\n")
    (bounded,) = [s for s in program.objects[2].specifiers if isinstance(s, ir.Direction)]
    assert (bounded.by.value, bounded.up_to.value) == (0.4, 0.6)
    (least,) = [s for s in program.objects[3].specifiers if isinstance(s, ir.Direction)]
    assert least.up_to is None and isinstance(least.by, ir.Distribution)


def test_the_rows_are_two_half_spaces_on_the_side_axis():
    support = Support(np.eye(3), np.array([0.05, 0.1, 0.2]), "exact")
    for relation, n in DIRECTION_AXES.items():
        poly = rows_direction(relation, np.array([1.0, 2.0, 3.0]), 0.4, support, 7, None, 0.6)
        half = float(np.abs(n) @ np.array([0.05, 0.1, 0.2]))
        assert np.allclose(poly.A, [-n, n]) and list(poly.labels) == [7, 7]
        base = float(n @ np.array([1.0, 2.0, 3.0])) + half
        assert np.allclose(poly.b, [-(base + 0.4), base + 0.6])
        assert len(poly.b) == 2 and poly.C.shape == (0, 3)


@pytest.mark.parametrize("relation, phrase", [("ahead", "ahead of"), ("left", "left of"), ("right", "right of")])
def test_sampled_gaps_fill_the_range_and_the_checker_agrees(tmp_path, relation, phrase):
    program = compile_text(tmp_path, f"c = Cube completely on t, {phrase} r by (0.3, 0.5)\n")
    scenes = list(Sampler(program, "exact").scenes(5, 200))
    gaps = [gap(s, "c", "r", relation) for s in scenes]
    assert all(0.3 - 1e-9 <= g <= 0.5 + 1e-9 for g in gaps)
    assert min(gaps) < 0.32 and max(gaps) > 0.48
    report = check_scenes(program, scenes)
    assert not report, report
    # The checker's new bound can fail: a scene with the cube 0.2 m further out is reported.
    bad = copy.deepcopy(scenes[0])
    cube = next(o for o in bad["objects"] if o["name"] == "c")
    cube["position"] = list(np.array(cube["position"]) + 0.2 * DIRECTION_AXES[relation])
    assert any("more than its greatest value" in problem for problem in check_scene(program, bad))


def test_a_bare_by_stays_at_least_d(tmp_path):
    program = compile_text(tmp_path, "c = Cube completely on t, ahead of r by 0.3\n")
    gaps = [gap(s, "c", "r", "ahead") for s in Sampler(program, "exact").scenes(5, 100)]
    assert min(gaps) >= 0.3 - 1e-9 and max(gaps) > 1.0  # far beyond 0.3: only a lower bound


def test_above_and_below_with_a_range(tmp_path):
    # from the plane through the table's centre (0.45 m below its top)
    program = compile_text(tmp_path, "lamp = Cube above t by (0.6, 0.7), aligned with t on x, aligned with t on y\n"
                                     "mat = Cube below lamp by (0.05, 0.1), aligned with t on x, aligned with t on y\n")
    for scene in Sampler(program, "exact").scenes(2, 20):
        assert 0.6 - 1e-9 <= gap(scene, "lamp", "t", "above") <= 0.7 + 1e-9
        assert 0.05 - 1e-9 <= gap(scene, "mat", "lamp", "below") <= 0.1 + 1e-9


@pytest.mark.parametrize("text, expected", [
    ("c = Cube ahead of r by (0.6, 0.4)\n",
     "bad.prs:4:24: error: `ahead of X by (low, high)` needs low <= high, not (0.6, 0.4)"),
    ("c = Cube left of r by (\"a\", 0.4)\n",
     "bad.prs:4:24: error: the least gap in `left of ... by (low, high)` must be a scalar, not a string"),
    ("c = Cube behind r by (0.1, Vector3D(0, 0, 1))\n",
     "bad.prs:4:28: error: the greatest gap in `behind ... by (low, high)` must be a scalar, not a vector"),
])
def test_bad_ranges_are_errors_at_the_range(tmp_path, capsys, text, expected):
    path = tmp_path / "bad.prs"
    path.write_text(H + text)
    assert main(["check", str(path)]) == 2
    assert capsys.readouterr().err.splitlines()[0].replace(str(path), "bad.prs") == expected
