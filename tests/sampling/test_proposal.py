"""Falsification proposals: they only reweight the spec's feasible set, learn where a controller
fails, and their importance weights give the failure probability under the spec's sequential law."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from prsc.commands.falsify import draw_round, falsify_rounds, verdicts
from prsc.commands.falsify_report import failure_clusters, weighted_estimate
from prsc.errors import PrscError
from prsc.ir import compile_program
from prsc.sampling import compile_sampler
from prsc.sampling.proposal import Component, Proposal, Strata
from tests.data.corner_controller import in_corner
from tests.sampling.scene_checks import check_scenes

SPEC = Path(__file__).resolve().parents[2] / "specs" / "table_cube.prs"
SEED = 3


def _rounds(rounds: int, size: int, method: str) -> tuple[list[dict], list[Proposal], list[dict]]:
    """Rounds of `method` against the corner controller, as prsc falsify runs them: (records, proposals used, scenes)."""
    sampler = compile_sampler(str(SPEC), law="sequential", proposal=Proposal())
    used, scenes = [], []

    def corner_round(number: int, drawn: list[dict], extras: list[dict]) -> list[dict]:
        used.append(sampler.proposal)
        scenes.extend(drawn)
        return [{"index": s["index"], "outcome": "corner" if in_corner(s) else "success", **e}
                for s, e in zip(drawn, extras)]

    records, _, _ = falsify_rounds(sampler, SEED, rounds * size, rounds, method, "label", None, corner_round)
    return records, used, scenes


@pytest.fixture(scope="module")
def corner_probability() -> tuple[float, float]:
    """The corner's probability under the spec's own law, by 4000 plain scenes: (p, its standard error)."""
    sampler = compile_sampler(str(SPEC))
    hits = [in_corner(sampler.scene(99, k)) for k in range(4000)]
    p = float(np.mean(hits))
    return p, math.sqrt(p * (1 - p) / len(hits))


@pytest.fixture(scope="module", params=["cross-entropy", "failure-tree"])
def campaign(request):
    return _rounds(6, 100, request.param)


def test_the_initial_proposal_is_the_spec_law():
    # Draw for draw the one-at-a-time sampler's scenes (Table-Cube's default batched sampler
    # draws the same law from another stream: docs/falsify.md).
    plain = compile_sampler(str(SPEC), batched=False)
    proposed = compile_sampler(str(SPEC), proposal=Proposal())
    for k in range(20):
        result = proposed.sample(0, k)
        assert result.context.proposal.weight() == 1.0
        assert plain.scene(0, k) == proposed.scene(0, k)


def test_proposal_concentrates_on_the_corner_within_a_few_rounds(campaign, corner_probability):
    records, used, _ = campaign
    p, _ = corner_probability
    by_round = [np.mean([r["outcome"] != "success" for r in records if r["round"] == k]) for k in range(len(used))]
    # Round 0 is the spec's law; by round 3 most scenes put the cube in the corner.
    assert by_round[0] < 3 * p
    assert by_round[3] > 0.5 and by_round[-1] > 0.5, by_round
    mass = np.full(64, 1 / 64)  # the tray's inside is a rectangle: its 8 x 8 cells weigh the same
    density = used[-1].site_density("position:c1", mass, 2)
    column, row = divmod(int(np.argmax(density)), 8)
    assert column >= 6 and row >= 5 and density.max() > 4, density  # the +x +y corner: x > 0.755, y > 0.6


def test_every_proposed_scene_satisfies_the_spec(campaign):
    _, _, scenes = campaign
    program = compile_program(SPEC)
    late = scenes[300:]  # drawn from the concentrated proposals
    problems = check_scenes(program, late)
    assert not problems, problems[:5]


def test_weighted_estimate_converges_to_the_corner_probability(campaign, corner_probability):
    records, _, _ = campaign
    p, se = corner_probability
    est = weighted_estimate(records, verdicts(records, None))
    tolerance = 3 * math.hypot(se, (est.high - est.low) / (2 * 1.96))
    assert abs(est.value - p) < tolerance, (est, p)
    assert est.low <= p <= est.high or abs(est.value - p) < tolerance
    # The test can fail: the raw failure fraction under the proposal (the wrong law) is far off.
    raw = np.mean([r["outcome"] != "success" for r in records])
    assert abs(raw - p) > 5 * tolerance, (raw, p, tolerance)


def test_a_round_gives_each_component_its_share_of_scenes_up_to_one():
    # Systematic choice: of 50 scenes, eps = 0.1 of them keep the spec's law and the components
    # (shares 0.3 and 0.7 of the rest) take 13.5 and 31.5, up to one, whatever the offset.
    left = Component(0.3, 0.0, {"position:c1": {0: 1.0}})
    right = Component(0.7, 0.0, {"position:c1": {63: 1.0}})
    for offset in (0.0, 0.37, 0.99):
        proposal = Proposal((left, right), 0.1, strata=Strata(100, 50, offset))
        sampler = compile_sampler(str(SPEC), proposal=proposal)
        picked = [sampler.sample(SEED, k).context.proposal.component for k in range(100, 150)]
        counts = [sum(c is None for c in picked), sum(c is left for c in picked), sum(c is right for c in picked)]
        assert counts[0] in (5, 6) and counts[1] in (13, 14) and counts[2] in (31, 32), (offset, counts)
        assert sum(counts) == 50


def test_failure_clusters_count_near_duplicates_once():
    base = {"outcome": "corner", "weight": 1.0}
    records = [{**base, "index": 0, "features": {"a": [0.1, 0.1]}}, {**base, "index": 1, "features": {"a": [0.15, 0.12]}},
               {**base, "index": 2, "features": {"a": [0.9, 0.9]}}, {**base, "index": 3, "outcome": "success",
                                                                     "features": {"a": [0.5, 0.5]}}]
    clusters = failure_clusters(records, verdicts(records, None))
    assert [c["episodes"] for c in clusters] == [[0, 1], [2]]


def test_a_bad_proposal_file_is_a_clear_error(tmp_path):
    bad = {"format": "prsc-proposal/1", "components": [{"share": 1, "spec_share": 0, "cells": {"position:c1": {"3": -1}}}]}
    with pytest.raises(PrscError, match="must be >= 0"):
        Proposal.from_json(bad)
    with pytest.raises(PrscError, match="not a prsc proposal"):
        Proposal.from_json({"weights": {}})


def test_importance_weights_average_one_under_a_learnt_proposal(campaign):
    # E_q[p / q] = 1 for any proposal: the trays (cells of the free space left by the robots),
    # the cube and the camera's ranges are all reweighted, and the ratios must account for it.
    _, used, _ = campaign
    _, info, _ = draw_round(compile_sampler(str(SPEC), proposal=used[-1]), SEED + 1, 0, 400)
    w = np.array([i["weight"] for i in info])
    assert {"position:tr_1", "position:c1"} <= set(info[0]["features"])
    assert w.std() > 0.3 and abs(w.mean() - 1.0) < 4 * w.std() / math.sqrt(len(w)), (w.mean(), w.std())
