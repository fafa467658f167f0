"""Candidate rounds (prsc/sampling/candidates.py): the joint law by whole-scene rejection,
vectorised over candidate scenes, with Gibbs sweeps where no candidate passes.

Their law is tested with the other joint-law samplers against the stored rejection
reference (test_joint_law.py: the tray of four cubes is drawn by candidate rounds). Here:
which specs they draw, that scene k is the same alone or in any chunk, and the geometry.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from prsc.geometry.obb import pair_overlaps, projection_overlaps
from prsc.geometry.rotations import quat_to_matrix
from prsc.sampling import compile_sampler
from prsc.sampling import candidates
from prsc.sampling.candidates import REJECTED

REPO = Path(__file__).resolve().parents[2]
BIN = REPO / "specs" / "bin_picking.prs"
TRAY = REPO / "tests" / "sampling" / "data" / "tray_four_cubes.prs"


def test_which_specs_candidate_rounds_draw():
    """Random sizes and yaws in a container and on a tray, `facing toward` from a fixed region or a random
    `at` point, `visible from` a camera are drawn by candidates; `stably on` is not."""
    assert compile_sampler(BIN).plan.path == "candidate rounds"
    assert compile_sampler(TRAY).plan.path == "candidate rounds"
    assert compile_sampler(REPO / "specs" / "facing_toward.prs").plan.path == "candidate rounds"
    assert compile_sampler(REPO / "specs" / "camera_view.prs").plan.path == "candidate rounds"
    assert compile_sampler(REPO / "specs" / "table_cube_reach.prs").plan.path == "candidate rounds"  # `reachable by`: hole and gap tested
    stack = compile_sampler(REPO / "specs" / "stack_and_cube.prs")
    assert stack.plan.path == "sequential + sweeps" and "stably" in stack.plan.why
    assert compile_sampler(BIN, law="sequential").plan.path != "candidate rounds"  # only the joint law
    assert compile_sampler(BIN, batched=False).plan.path != "candidate rounds"  # one scene at a time: Gibbs sweeps


@pytest.mark.parametrize("spec", [BIN, TRAY])
def test_scene_k_is_the_same_alone_or_in_any_chunk(spec):
    sampler = compile_sampler(spec)
    together = sampler.batch(3, range(0, 70))  # more than one chunk of scenes
    alone = [sampler.scene(3, k) for k in (0, 41, 69)]
    shifted = sampler.batch(3, range(41, 45))
    assert [together[k] for k in (0, 41, 69)] == alone
    assert together[41:45] == shifted
    assert together[0] != together[1]


def test_candidate_scenes_hold_the_spec():
    """Every part lies inside the bin's walls, on its floor, and no two boxes overlap."""
    sampler = compile_sampler(BIN)
    results = sampler.results(0, range(64))
    assert sum(r.stats.counts.get(REJECTED, 0) for r in results) > 64  # candidates were rejected, not all drawn first
    for result in results:
        objects = {o.name: o for o in result.objects}
        bin_ = objects["bin_1"]
        inner = np.array(bin_.dims[:2]) / 2 - bin_.props["wallThickness"]
        parts = [o for name, o in objects.items() if name.startswith(("part_", "can_"))]
        for part in parts:
            corners = np.abs(part.rotation[:2, :2]) @ (np.array(part.dims[:2]) / 2)
            assert np.all(np.abs(part.position[:2] - bin_.position[:2]) + corners <= inner + 1e-9)
            floor = bin_.position[2] - bin_.dims[2] / 2 + bin_.props["floorThickness"]
            assert part.position[2] - part.dims[2] / 2 == pytest.approx(floor)
        for i, a in enumerate(parts):
            for b in parts[:i]:
                overlap = pair_overlaps(a.position[None], a.rotation[None], np.array(a.dims)[None] / 2,
                                        b.position[None], b.rotation[None], np.array(b.dims)[None] / 2)
                assert overlap[0] <= 1e-6


def test_a_packed_spec_is_left_to_gibbs_sweeps_by_the_pilot():
    """Ten cubes in a tray: hardly a candidate passes, so the pilot leaves the spec to Gibbs sweeps
    (here run over many scenes at once: test_group_gibbs.py)."""
    sampler = compile_sampler(REPO / "specs" / "ten_cubes_tray.prs")
    sampler.scene(0, 0)
    assert sampler.plan.path == "Gibbs rounds"
    assert "pilot" in sampler.plan.why


def test_a_scene_without_a_passing_candidate_is_the_gibbs_samplers(monkeypatch):
    """With a budget of 64 candidates most bin_picking scenes find none: those are drawn by the
    Gibbs sweeps (the same scene as without candidate rounds), the others are candidates. (4 before
    the library Panda's box became its file's, 0.58 m deep: its bin now stands nearer the edge.)"""
    sampler = compile_sampler(BIN)
    assert sampler.plan.path == "candidate rounds"  # the pilot ran with the real budget
    monkeypatch.setattr(candidates, "BUDGET", 64)
    gibbs = compile_sampler(BIN, batched=False)
    results = sampler.results(0, range(12))
    drawn = [REJECTED in r.stats.counts or r.stats.total == 0 for r in results]
    assert 0 < sum(drawn) < 12
    for index, (result, by_candidate) in enumerate(zip(results, drawn)):
        if not by_candidate:
            assert sampler.to_json(result, 0, index) == gibbs.scene(0, index)


def test_pair_overlaps_is_the_sat_of_each_pair():
    rng = np.random.default_rng(0)
    n = 300
    ca, cb = rng.normal(size=(n, 3)) * 0.3, rng.normal(size=(n, 3)) * 0.3
    ra, rb = quat_to_matrix(rng.normal(size=(n, 4))), quat_to_matrix(rng.normal(size=(n, 4)))
    ha, hb = rng.uniform(0.05, 0.3, (n, 3)), rng.uniform(0.05, 0.3, (n, 3))
    got = pair_overlaps(ca, ra, ha, cb, rb, hb)
    want = [projection_overlaps(ca[i], ra[i], ha[i], cb[i:i + 1], rb[i:i + 1], hb[i:i + 1]).min() for i in range(n)]
    assert np.allclose(got, want, atol=1e-12)
    assert 0.1 < np.mean(got > 0) < 0.9  # both colliding and separated pairs


REACH_SPEC = """\
from tabletop import *
table = Table on Vector3D(0, 0, 0), with width 1.8, with length 1.2, with height 0.75
arm = Robot on (top back table).position + Vector3D(0, 0.25, 0)
cube = Cube completely on table, reachable by arm
"""


def _reach_draws(scenes: list[dict]) -> np.ndarray:
    """The cube's x and y in each scene."""
    return np.array([next(o for o in s["objects"] if o["name"] == "cube")["position"][:2] for s in scenes])


def test_reachable_by_is_uniform_on_the_table_within_the_ring_less_its_hole(tmp_path):
    """`reachable by`'s excluded cells are candidate tests: the cube is uniform on the table's top
    within the outer cell and out of the hole about the base. The reference is numpy's own
    rejection from the table's top against the ring (reach_ring.contains); the same test fails
    for the law that forgets the hole (drawn the same way), so it can fail."""
    from scipy.stats import ks_2samp

    from prsc.constraints.arm_reach import arm_reach
    from prsc.user_assets.asset_files import model_asset
    from prsc.constraints.reach_ring import contains

    spec = tmp_path / "reach.prs"
    spec.write_text(REACH_SPEC)
    sampler = compile_sampler(spec)
    assert sampler.plan.path == "candidate rounds"
    drawn = _reach_draws(sampler.batch(3, list(range(2000))))
    scene = sampler.scene(3, 0)
    objects = {o["name"]: o for o in scene["objects"]}
    arm, cube, table = objects["arm"], objects["cube"], objects["table"]
    rotation = quat_to_matrix(arm["quaternion"])
    base = np.asarray(arm["position"]) + rotation @ np.asarray(arm["properties"]["rootOffset"])
    half = (np.asarray(table["dimensions"][:2]) - np.asarray(cube["dimensions"][:2])) / 2
    rng = np.random.default_rng(5)
    points = np.column_stack([rng.uniform(-half, half, (200_000, 2)), np.full(200_000, cube["position"][2])])
    local = (points - base) @ rotation
    ring = arm_reach(model_asset(arm["model"])).ring
    empty = (np.array([[0.0, 0.0, 0.0]]), np.array([-1.0]))  # a cell no point is in
    no_hole = type(ring)(ring.a, ring.b, *empty, *empty)
    for law, expected in ((ring, True), (no_hole, False)):
        reference = points[contains(law, local), :2][:4000]
        assert len(reference) == 4000
        pvalues = [ks_2samp(drawn[:, k], reference[:, k]).pvalue for k in range(2)]
        pvalues.append(ks_2samp(np.hypot(*(drawn - base[:2]).T), np.hypot(*(reference - base[:2]).T)).pvalue)
        assert (min(pvalues) >= 0.01) == expected, (expected, pvalues)


def test_a_carried_region_tested_against_a_reach_ring_follows_the_gibbs_sweeps():
    """table_cube_reach's cube is carried by its tray and cut by the Panda's ring, whose hundred
    rows are tested per candidate rather than cut (candidate_cuts.MAX_CUT_ROWS): its positions
    and the target tray's follow the Gibbs sweeps' (KS per coordinate, fixed seeds)."""
    from scipy.stats import ks_2samp

    spec = REPO / "specs" / "table_cube_reach.prs"
    sampler = compile_sampler(spec)
    assert sampler.plan.path == "candidate rounds"
    drawn = sampler.batch(4, list(range(2000)))
    gibbs = compile_sampler(spec, batched=False)
    reference = [gibbs.scene(5, k) for k in range(300)]

    def coordinate(scenes, name, k):
        return [next(o for o in s["objects"] if o["name"] == name)["position"][k] for s in scenes]

    pvalues = [ks_2samp(coordinate(drawn, name, k), coordinate(reference, name, k)).pvalue
               for name in ("c1", "tr_1", "tr_2") for k in range(2)]
    assert min(pvalues) >= 0.01, pvalues
