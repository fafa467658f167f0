"""`reachable by R` for the library's Panda: its ring from the one builder against the one IK, and the specifier on it."""

from __future__ import annotations

import json
import math
import os
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from prsc.constraints import lower_program
from prsc.constraints.arm_reach import TopDownIK, arm_reach
from prsc.errors import PrscError
from prsc.geometry.polytope import Polytope
from prsc.constraints.reach_ring import contains
from prsc.geometry.uniform_sampling import prepare_sampler
from prsc.ir import compile_program
from prsc.sampling import Sampler
from prsc.user_assets.asset_files import model_asset

REPO = Path(__file__).resolve().parents[2]
REACH_SPEC = REPO / "specs" / "table_cube_reach.prs"


@pytest.fixture(scope="module")
def panda():
    """The library's Panda: its description and the one IK on its model (prsc/user_assets/arm_ik.py)."""
    asset = model_asset("panda")
    return asset, arm_reach(asset).ring, TopDownIK(asset)


def _points(a: np.ndarray, b: np.ndarray, n: int, seed: int) -> np.ndarray:
    return prepare_sampler(Polytope.from_rows(a, b)).sample(np.random.default_rng(seed), n)


def test_the_library_arms_ring_comes_from_the_one_builder(panda):
    asset, ring, _ = panda
    assert asset.fitting is not None and asset.tcp == "tcp"
    assert not (REPO / "prsc" / "constraints" / "panda_reach.json").exists()
    data = json.loads((Path(os.environ["PRSC_BUILD_DIR"]) / "reach").glob(f"{asset.key}-tcp-*.json").__next__()
                      .read_text(encoding="utf-8"))
    assert data["sha256"] == asset.digest and len(data["A"]) == len(ring.b)


def test_points_in_the_ring_are_reached_top_down_and_points_past_it_are_not(panda):
    _, ring, ik = panda
    a, b = ring.a, ring.b
    candidates = _points(a, b, 60, seed=1)
    inside = candidates[contains(ring, candidates)][:12]
    assert len(inside) == 12
    # Some lie beside and behind the base.
    assert (inside[:, 1] < 0).sum() >= 2
    assert all(ik.reaches_from_home(p) for p in inside), "a point of the ring is out of the arm's reach"
    # The same test fails on a wrong cell: pushed 30 cm out, the part past the longest
    # radius the ring keeps (plus 5 cm) is out of reach.
    longest = max(math.hypot(*p[:2]) for p in _points(a, b, 400, seed=3))
    outer = a[:, :2].any(axis=1) & (b > 0)
    candidates = _points(a, b + np.where(outer, 0.3, 0.0), 400, seed=2)
    beyond = [p for p in candidates if math.hypot(p[0], p[1]) > longest + 0.05][:6]
    assert len(beyond) == 6 and not any(ik.reaches_from_home(p) for p in beyond)


def _beside_the_hole(ring, band: float) -> np.ndarray:
    """Kept points at the root's height within `band` of the hole, on a 1 cm grid (offset 5 mm:
    not the builder's own polar check points)."""
    xs = np.arange(-0.455, 0.46, 0.01)
    grid = np.array([[x, y, 0.0] for x in xs for y in xs])
    grid = grid[contains(ring, grid)]
    inside = (grid[:, None, :] - band * np.array([[math.cos(t), math.sin(t), 0.0] for t in np.arange(0, 2 * math.pi, math.pi / 8)]))
    hole = (np.einsum("ij,pkj->pki", ring.hole_a, inside) <= ring.hole_b).all(axis=2)
    return grid[hole.any(axis=1)]


def test_every_point_kept_beside_the_hole_is_reached_from_home(panda):
    # Beside the base the IK from home is ragged: before the builder checked the hole's edge,
    # 34 such points of the Panda's ring at its root's height were not reached.
    _, ring, ik = panda
    near = _beside_the_hole(ring, 0.02)
    assert len(near) > 300
    missed = [p.round(3).tolist() for p in near if not ik.reaches_from_home(p)]
    assert not missed, f"{len(missed)} of {len(near)} kept points beside the hole are not reached: {missed}"
    # The same check fails on a wrong cell: the hole shrunk to half keeps points the IK misses.
    gap = {"gap_b": ring.hole_b / 2} if np.array_equal(ring.gap_b, ring.hole_b) else {}  # the reach goes all round
    shrunk = replace(ring, hole_b=ring.hole_b / 2, **gap)
    new = sorted(_beside_the_hole(shrunk, 0.02), key=lambda p: math.hypot(p[0], p[1]))
    assert len(new) >= 10
    assert sum(not ik.reaches_from_home(p) for p in new[:10]) >= 5


def test_reachable_cubes_are_sampled_exactly_inside_the_ring_and_reached_by_the_one_ik(panda):
    asset, ring, ik = panda
    program = compile_program(str(REACH_SPEC), ())
    cprog = lower_program(program)
    c1 = next(p for p in cprog.objects if p.name == "c1")
    rule = next(r for r in c1.rules if r.kind == "reachable")
    # r1 is fixed: the rule's rows are static, and the cube's region still moves with its tray.
    assert rule.static and c1.region.anchor == "tr_1"
    # One scene at a time (Gibbs sweeps): the hole and the gap subtracted exactly, nothing rejected.
    # (Candidate rounds, the default for many scenes, test them instead: tests/sampling/test_candidates.py.)
    sampler = Sampler(program, "exact", batched=False)
    inside, local = 0, []
    for index in range(300):
        result = sampler.sample(11, index)
        assert result.stats.total == 0
        objects = {o.name: o for o in result.objects}
        robot = objects["r1"]
        root = robot.position + robot.rotation @ np.asarray(robot.props["rootOffset"])
        q = robot.rotation.T @ (objects["c1"].position - root)
        inside += bool(contains(ring, q, tol=1e-7)[0])
        local.append(q)
    assert inside == 300
    local = np.array(local)
    # They spread over the reachable part of the tray: both near and far from the base.
    radius = np.hypot(local[:, 0], local[:, 1])
    assert radius.min() < 0.55 and radius.max() > 0.7
    # Every cube (centre) of the first 20 scenes is reached top-down by the one IK.
    assert all(ik.reaches_from_home(q) for q in local[:20])


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
