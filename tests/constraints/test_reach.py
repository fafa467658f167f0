"""`reachable by R`: the shipped reachable-set data against the arm's IK, and the specifier on it."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from prsc.constraints import lower_program
from prsc.constraints.reach_rows import reach_ring, reach_file
from prsc.errors import PrscError
from prsc.geometry.polytope import Polytope
from prsc.constraints.reach_ring import contains
from prsc.geometry.uniform_sampling import prepare_sampler
from prsc.ir import compile_program
from prsc.sampling import Sampler

REPO = Path(__file__).resolve().parents[2]
REACH_SPEC = REPO / "specs" / "table_cube_reach.prs"


@pytest.fixture(scope="module")
def arm():
    from prsc.commands.reach import TopDownReach

    return TopDownReach()


def _points(a: np.ndarray, b: np.ndarray, n: int, seed: int) -> np.ndarray:
    return prepare_sampler(Polytope.from_rows(a, b)).sample(np.random.default_rng(seed), n)


def test_the_ring_is_what_the_script_derives_from_its_ik_rays():
    from prsc.commands import reach

    data = json.loads(reach_file("panda").read_text(encoding="utf-8"))
    assert data["heights"] == list(reach.HEIGHTS) and len(data["angles"]) == reach.SECTORS
    rays = {(k, j): (None if lo is None else (lo, hi)) for k, j, lo, hi in data["rays"]}
    derived = reach.reach_data(rays)
    for key, value in derived["ring"].items():
        np.testing.assert_allclose(np.array(data["ring"][key]), np.array(value), atol=1e-12)


def test_points_in_the_ring_are_reached_top_down_and_points_past_it_are_not(arm):
    ring = reach_ring("panda")
    a, b = ring.a, ring.b
    candidates = _points(a, b, 60, seed=1)
    inside = candidates[contains(ring, candidates)][:12]
    assert len(inside) == 12
    # Some lie beside and behind the base (the old single cell kept only the half ahead, y > 0).
    assert (inside[:, 1] < 0).sum() >= 2
    assert all(arm.reaches(p) for p in inside), "a point of the shipped ring is out of the arm's reach"
    # The same test fails on a wrong cell: pushed 30 cm out, the part past the longest
    # radius the IK scan found (plus 5 cm) is out of reach.
    data = json.loads(reach_file("panda").read_text(encoding="utf-8"))
    longest = max(hi for _, _, lo, hi in data["rays"] if hi is not None)
    outer = a[:, :2].any(axis=1) & (b > 0)
    candidates = _points(a, b + np.where(outer, 0.3, 0.0), 400, seed=2)
    beyond = [p for p in candidates if math.hypot(p[0], p[1]) > longest + 0.05][:6]
    assert len(beyond) == 6 and not any(arm.reaches(p) for p in beyond)


def test_a_pose_with_the_hand_inside_the_base_is_not_reached(arm):
    # Beside the base at its height the IK puts the tool on the point, with the hand in link0.
    point = np.array([0.1, 0.05, 0.0])
    solution = arm.ik.solve(point, arm.down, arm.home)
    assert solution.position_error < 1e-3 and solution.orientation_error < 1e-2
    assert arm.ik.self_collides(solution.q) and not arm.ik.self_collides(arm.home)
    assert not arm.ik.solve_free(point, arm.down, arm.home).reached
    assert not arm.reaches(point)


def test_a_point_home_alone_misses_is_sought_from_home_turned_towards_it(arm):
    # 0.66 m out at 75 degrees to the left, 12 cm up (a cube's approach): the IK from home stalls
    # 12 cm short; from home turned towards it, wrist turned back, it gets there.
    above = np.array([-0.638, 0.171, 0.12])
    assert arm.ik.solve(above, arm.down, arm.home).position_error > 0.05
    assert arm.ik.solve_from_home(above, arm.down).reached
    assert arm.reaches(above - [0.0, 0.0, 0.12])


def test_the_constraint_stage_reads_data_and_never_imports_mujoco():
    code = (
        "import sys; from prsc.ir import compile_program; from prsc.constraints import lower_program;"
        f"lower_program(compile_program({str(REACH_SPEC)!r}, ()));"
        "print(sorted(m for m in ('mujoco', 'mink', 'prsc.backends') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_reachable_cubes_are_sampled_exactly_inside_the_cell_and_fill_it():
    program = compile_program(str(REACH_SPEC), ())
    cprog = lower_program(program)
    c1 = next(p for p in cprog.objects if p.name == "c1")
    rule = next(r for r in c1.rules if r.kind == "reachable")
    # r1 is fixed: the rule's rows are static, and the cube's region still moves with its tray.
    assert rule.static and c1.region.anchor == "tr_1"
    # One scene at a time (Gibbs sweeps): the hole and the gap subtracted exactly, nothing rejected.
    # (Candidate rounds, the default for many scenes, test them instead: tests/sampling/test_candidates.py.)
    sampler = Sampler(program, "exact", batched=False)
    ring = reach_ring("panda")
    inside, local = 0, []
    for index in range(300):
        result = sampler.sample(11, index)
        assert result.stats.total == 0
        objects = {o.name: o for o in result.objects}
        robot = objects["r1"]
        base = robot.position - robot.rotation[:, 2] * robot.dims[2] / 2
        q = robot.rotation.T @ (objects["c1"].position - base)
        inside += bool(contains(ring, q, tol=1e-7)[0])
        local.append(q)
    assert inside == 300
    local = np.array(local)
    # They spread over the reachable part of the tray: both near and far from the base.
    radius = np.hypot(local[:, 0], local[:, 1])
    assert radius.min() < 0.35 and radius.max() > 0.7


def test_reachable_by_an_unknown_model_or_a_point_is_an_error_at_the_specifier(tmp_path):
    spec = tmp_path / "ur.prs"
    spec.write_text(
        "from tabletop import *\n"
        "arm = Robot at Vector3D(0, 0, 0.52), with model \"ur5\"\n"
        "c = Cube at Vector3D((0.2, 0.3), 0.4, 0.1), reachable by arm\n", encoding="utf-8")
    with pytest.raises(PrscError, match=r"'reachable by' needs a robot .*; arm's model is 'ur5'") as caught:
        lower_program(compile_program(str(spec), ()))
    assert caught.value.span.line == 3
    spec.write_text("from tabletop import *\nc = Cube reachable by Vector3D(0, 0, 1)\n", encoding="utf-8")
    with pytest.raises(PrscError, match="`reachable by` needs a robot object, not a vector"):
        compile_program(str(spec), ())


def test_explain_shows_the_rows_and_their_source(capsys):
    from prsc.cli import main

    line = next(i for i, text in enumerate(REACH_SPEC.read_text().splitlines(), 1) if text.startswith("c1 = "))
    assert main(["explain", str(REACH_SPEC)]) == 0
    out = capsys.readouterr().out
    assert f"reachable by r1  [containment; {REACH_SPEC}:{line}]" in out
    assert main(["explain", str(REACH_SPEC), "--json"]) == 0
    entry = next(e for e in json.loads(capsys.readouterr().out)["rules"] if e["kind"] == "reachable" and e["object"] == "c1")
    assert entry["line"] == line and entry["rows_are"] == "the same in every scene" and len(entry["rows"]["A"]) > 4
    assert not math.isnan(entry["rows"]["b"][0])


def test_the_reach_builder_certifies_the_controllers_own_heights(arm, monkeypatch):
    """The Panda's reach builder reads the handover's approach and lift (prsc/runner/grasping.py),
    not copies of them: a lift no arm makes leaves a point it reaches out of reach."""
    from prsc.commands.reach import TopDownReach
    from prsc.runner import grasping

    point = np.array([0.0, 0.45, 0.05])
    assert arm.reaches(point)
    monkeypatch.setattr(grasping, "LIFT_HEIGHT", 3.0)
    assert not TopDownReach().reaches(point)
