"""Sequential placement: backtracking, obstacles, the joint law, the other samplers."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.stats import chisquare

from prsc.errors import PrscError
from prsc.ir import compile_program
from prsc.sampling import Sampler
from prsc.sampling.stats import RejectionStats
from tests.sampling.scene_checks import check_scene, check_scenes
from tests.original import ORIGINAL, needs_original

REPO = Path(__file__).resolve().parents[2]
MANY = REPO / "tests" / "sampling" / "data" / "many_specifiers.prs"


def _sampler(tmp_path, text, name="exact", **opts):
    spec = tmp_path / "spec.prs"
    spec.write_text("from tabletop import *\n" + text)
    program = compile_program(str(spec), ())
    return Sampler(program, name, **opts), program


def test_a_dead_end_backtracks_to_the_object_it_depends_on(tmp_path):
    sampler, program = _sampler(
        tmp_path,
        "t = Table on Vector3D(0, 0, 0), with width 1.0, with length 0.4, with height 0.5\n"
        "a = Cube completely on t\n"
        "b = Box completely on t, left of a by 0.2\n",
        batched=False,  # the engine's own dead ends (by default candidate rounds draw this spec)
    )
    stats = RejectionStats()
    for i in range(200):
        result = sampler.sample(0, i)
        stats.merge(result.stats)
        a = result.objects[1].position
        assert a[0] >= 0.0 - 1e-9  # only placements of a that leave room for b survive
    assert stats.counts.get("dead end", 0) > 20
    assert check_scene(program, sampler.scene(0, 5)) == []


def test_no_free_position_is_proven_and_the_blocker_re_placed(tmp_path):
    sampler, program = _sampler(
        tmp_path,
        "t = Table on Vector3D(0, 0, 0), with width 0.7, with length 0.3, with height 0.5\n"
        "a = Box completely on t\n"
        "b = Box completely on t\n",
    )
    scenes = [sampler.scene(4, i) for i in range(100)]
    assert not check_scenes(program, scenes)
    for scene in scenes:
        xa, xb = (o["position"][0] for o in scene["objects"][1:])
        assert abs(xa - xb) >= 0.3 - 1e-9


def test_joint_law_differs_from_sequential_and_matches_a_reference(tmp_path):
    text = (
        "t = Table on Vector3D(0, 0, 0), with width 0.6, with length 0.04, with height 0.5\n"
        "a = Cube with width 0.2, completely on t\n"
        "b = Cube with width 0.2, completely on t\n"
    )
    seq, _ = _sampler(tmp_path, text, law="sequential")
    joint, program = _sampler(tmp_path, text, law="rejection")
    gibbs, _ = _sampler(tmp_path, text)  # the default law: the joint one, by Gibbs sweeps
    n, k = 3000, 8
    edges = np.linspace(-0.2, 0.2, k + 1)

    def hist(sampler):
        xs = np.array([sampler.sample(3, i).objects[1].position[0] for i in range(n)])
        return np.histogram(xs, edges)[0]

    # Sequential: a is uniform on its region. Joint: pairs uniform on the non-overlapping set.
    assert chisquare(hist(seq)).pvalue > 1e-3
    rng = np.random.default_rng(0)
    pairs = rng.uniform(-0.2, 0.2, (2_000_000, 2))
    ok = np.abs(pairs[:, 0] - pairs[:, 1]) >= 0.2
    ref = np.histogram(pairs[ok, 0], edges)[0].astype(float)
    observed = hist(joint)
    assert chisquare(observed, ref / ref.sum() * n).pvalue > 1e-3
    assert chisquare(observed).pvalue < 1e-6  # and clearly not uniform
    assert chisquare(hist(gibbs), ref / ref.sum() * n).pvalue > 1e-3
    assert check_scene(program, joint.scene(3, 1)) == []


def test_allow_collisions_and_facing_toward(tmp_path):
    sampler, program = _sampler(
        tmp_path,
        "t = Table on Vector3D(0, 0, 0), with width 1, with length 1, with height 0.5\n"
        "ghost = Box at Vector3D(0, 0, 0.6), with allowCollisions True\n"
        "c = Bin completely on t, facing toward ghost\n",
    )
    scenes = [sampler.scene(0, i) for i in range(50)]
    assert not check_scenes(program, scenes)
    for scene in scenes:
        ghost, c = scene["objects"][1], scene["objects"][2]
        # A Box declares its interior (the model library) besides the allowCollisions set here.
        assert ghost["properties"] == {"allowCollisions": True, "container": "box", "floorThickness": 0.006, "wallThickness": 0.006}
        w, x, y, z = c["quaternion"]
        assert abs(x) < 1e-12 and abs(y) < 1e-12  # a yaw only


def test_hit_and_run_walk_length_is_used(tmp_path):
    short, program = _sampler(tmp_path, "c = Cube completely in Cuboid(Vector3D(0, 0, 1), Vector3D(0, 0, 0), 1, 1, 1)\n", "hit-and-run", walk_length=1)
    long, _ = _sampler(tmp_path, "c = Cube completely in Cuboid(Vector3D(0, 0, 1), Vector3D(0, 0, 0), 1, 1, 1)\n", "hit-and-run", walk_length=50)
    one_step = np.array([short.sample(0, i).objects[0].position for i in range(300)])
    many = np.array([long.sample(0, i).objects[0].position for i in range(300)])
    # One step from the centre stays on a chord through it; a long walk spreads out.
    assert np.mean(np.linalg.norm(one_step - [0, 0, 1], axis=1)) < np.mean(np.linalg.norm(many - [0, 0, 1], axis=1))
    assert check_scene(program, long.scene(0, 0)) == []


def test_an_unbounded_region_is_a_clear_error(tmp_path):
    spec = tmp_path / "open.prs"
    spec.write_text("class Cube:\n    width: 0.1\nc = Cube left of Vector3D(0, 0, 0)\n")
    with pytest.raises(PrscError, match="unbounded"):
        Sampler(compile_program(str(spec), ())).scene(0, 0)


@needs_original
def test_baseline_counts_rejections_by_cause_and_exact_rejects_nothing():
    program = compile_program(str(ORIGINAL / "tableCube.prs"), ())
    naive = compile_program(str(ORIGINAL / "tableCubeNaive.prs"), ())
    for prog, causes in ((program, ("relative position", "containment")), (naive, ("require",))):
        base, exact = RejectionStats(), RejectionStats()
        rej_sampler, exact_sampler = Sampler(prog, "baseline"), Sampler(prog, "exact")
        for i in range(20):
            base.merge(rej_sampler.sample(2, i).stats)
            exact.merge(exact_sampler.sample(2, i).stats)
        assert not check_scenes(prog, [rej_sampler.scene(2, i) for i in range(20)])
        assert exact.total == 0
        assert all(base.counts.get(c, 0) > 0 for c in causes)
        assert base.total / 20 > 50  # the paper: about 200 per scene


def test_many_specifiers_spec_is_valid_under_exact_and_hit_and_run():
    program = compile_program(str(MANY), ())
    for name, n in (("exact", 150), ("hit-and-run", 10)):
        sampler = Sampler(program, name)
        report = check_scenes(program, [sampler.scene(6, i) for i in range(n)])
        assert not report, (name, report)


@pytest.mark.parametrize("name", ["exact", "baseline"])
def test_a_solver_failure_while_sampling_is_an_error_at_the_object(tmp_path, monkeypatch, name):
    """A region rebuilt per scene (random table size) whose LP fails numerically: exit 2 at the object."""
    from prsc.geometry.exceptions import GeometryError
    from prsc.sampling import prepared

    sampler, _ = _sampler(tmp_path, "t = Table on Vector3D(0, 0, 0), with width (1, 2)\nc = Cube completely on t\n", name)

    def failing(poly):
        raise GeometryError("HiGHS failed on a 12x4 LP: Not Set")

    monkeypatch.setattr(prepared, "prepare_sampler", failing)
    with pytest.raises(PrscError, match="cannot place c: its constraints could not be solved numerically") as info:
        sampler.sample(0, 0)
    assert (info.value.span.line, info.value.span.column) == (3, 1)


def test_the_failure_message_counts_the_attempts_really_made(tmp_path):
    """With --law rejection the work budget ends a hopeless scene long before 100000 attempts: say so."""
    import re

    sampler, _ = _sampler(
        tmp_path,
        "t = Table on Vector3D(0, 0, 0), with width (0.2, 0.3), with length (0.2, 0.3)\n"
        "c = Cube completely on t, with width 1.0, with length 1.0\n",
        law="rejection",
    )
    with pytest.raises(PrscError) as info:
        sampler.sample(0, 0)
    tried = int(re.search(r"in (\d+) attempts", info.value.message).group(1))
    assert 0 < tried < sampler._engine.limits.joint_attempts
