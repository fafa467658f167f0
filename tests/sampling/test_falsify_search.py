"""`prsc falsify`'s search driven by a synthetic episode (no MuJoCo): robustness steers it to rare failures,
its weighted estimate stays on the spec's law, and its intervals are honest at the edges.

The synthetic episode is a deterministic function of the sampled scene, written as the task
monitor writes an episode's record (prsc/commands/falsify_property.py): the robustness of
`fail "corner" when ...` is the distance of the cube from the +x +y corner of its feasible
region in its tray, minus a radius. Table-Cube's cube is uniform on that region (0.177 x 0.393 m),
so the failure probability is the quarter disc's share of it."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import binom

from prsc.commands.falsify import falsify_rounds, verdicts
from prsc.commands.falsify_property import episode_verdict
from prsc.commands.falsify_report import clopper_pearson, failure_estimate, weighted_estimate
from prsc.errors import PrscError
from prsc.sampling import compile_sampler
from prsc.sampling.proposal import Proposal
from prsc.sampling.proposal_search import elite_level, near_failures
from tests.data.corner_controller import CORNER, in_corner

SPEC = Path(__file__).resolve().parents[2] / "specs" / "table_cube.prs"
# The +x +y corner of the cube's feasible region in its tray: the tray's inside less the cube's half size.
CX, CY = 0.2364 / 2 - 0.0095 - 0.02, 0.4522 / 2 - 0.0095 - 0.02
RARE = 0.016  # metres: P(failure) = pi RARE^2 / 4 / (2 CX 2 CY) = 0.0029 under the spec's law
UNCOMMON = 0.036  # P = 0.0146: rare enough to need steering, common enough for a uniform interval to see it


def corner_distance(scene: dict) -> float:
    """The cube's distance from the +x +y corner of its feasible region in tr_1 (metres)."""
    objects = {o["name"]: o for o in scene["objects"]}
    cube, tray = objects["c1"]["position"], objects["tr_1"]["position"]
    return math.hypot(CX - (cube[0] - tray[0]), CY - (cube[1] - tray[1]))


def task_record(outcome: str, robustness: dict) -> dict:
    """An episode's task record as the task monitor of `prsc run` writes it."""
    return {"outcome": outcome, "trivial": False, "decided_at": None, "robustness": robustness, "records": {}}


def corner_episodes(radius: float):
    """A round runner whose episode fails `corner` when the cube is within `radius` of the corner."""
    def run_round(number: int, scenes: list[dict], extras: list[dict]) -> list[dict]:
        records = []
        for scene, extra in zip(scenes, extras):
            rho = corner_distance(scene) - radius
            task = task_record("fail:corner" if rho < 0 else "success", {"goal": 1.0, "fail:corner": rho})
            records.append({"index": scene["index"], "outcome": "success", "task": task, **extra})
        return records
    return run_round


@pytest.fixture(scope="module")
def sampler():
    """One compiled sampler for every campaign (falsify_rounds sets each round's proposal)."""
    return compile_sampler(str(SPEC), law="sequential", proposal=Proposal())


def campaign(sampler, seed: int, radius: float, steer: str, method: str = "failure-tree", budget: int = 200,
             rounds: int = 10) -> tuple[list[dict], list]:
    records, _, _ = falsify_rounds(sampler, seed, budget, rounds, method, steer, "corner", corner_episodes(radius))
    return records, verdicts(records, "corner")


def test_the_synthetic_failure_is_rare_under_the_spec_law():
    assert math.pi * RARE ** 2 / 4 / (4 * CX * CY) == pytest.approx(0.0029, abs=1e-4)
    assert math.pi * UNCOMMON ** 2 / 4 / (4 * CX * CY) == pytest.approx(0.0146, abs=1e-4)


def test_robustness_finds_three_times_the_rare_failures_of_labels(sampler):
    # Budget 200, 10 rounds, the same seeds: measured 48 and 19 failures steered by robustness,
    # 0 and 0 by the labels alone (which never see a failure to move toward).
    found = {}
    for seed in (2, 3):
        for steer in ("robustness", "label"):
            _, judged = campaign(sampler, seed, RARE, steer)
            found[seed, steer] = sum(v.failed for v in judged)
    for seed in (2, 3):
        assert found[seed, "robustness"] >= max(3 * found[seed, "label"], 10), found


def test_where_nothing_fails_robustness_gets_three_times_closer(sampler):
    # Radius 0: no scene fails. Measured lowest distance 1.6 mm against uniform's 19.5 mm (seed 2).
    _, steered = campaign(sampler, 2, 0.0, "robustness")
    _, uniform = campaign(sampler, 2, 0.0, "label", method="uniform")
    assert not any(v.failed for v in steered + uniform)
    lowest, baseline = min(v.robustness for v in steered), min(v.robustness for v in uniform)
    assert lowest <= baseline / 3, (lowest, baseline)


def test_weighted_estimate_stays_inside_the_uniform_interval(sampler):
    records, judged = campaign(sampler, 0, UNCOMMON, "robustness")
    uniform, uniform_judged = campaign(sampler, 100, UNCOMMON, "label", method="uniform", budget=400, rounds=1)
    reference = weighted_estimate(uniform, uniform_judged)
    assert reference.basis.startswith("exact") and 0 < reference.low < 0.0146 < reference.high
    est = weighted_estimate(records, judged)
    assert reference.low <= est.value <= reference.high, (est, reference)
    # The check can fail: the raw failure fraction under the proposal (the proposal's law, not the spec's)
    # is far outside.
    raw = np.mean([v.failed for v in judged])
    assert raw > 3 * reference.high, (raw, reference)


def test_robustness_does_no_worse_than_labels_on_common_failures(sampler):
    # The corner controller's failure (tests/data/corner_controller.py: 8.7 % of the spec's law),
    # with its robustness: how far the cube is from entering the corner. Measured 120 and 120 failures.
    def run_round(number, scenes, extras):
        out = []
        for scene, extra in zip(scenes, extras):
            objects = {o["name"]: o for o in scene["objects"]}
            cube, tray = objects["c1"]["position"], objects["tr_1"]["position"]
            rho = -min(cube[0] - tray[0] - CORNER[0], cube[1] - tray[1] - CORNER[1])
            task = task_record("fail:corner" if in_corner(scene) else "success", {"goal": 1.0, "fail:corner": rho})
            out.append({"index": scene["index"], "outcome": "success", "task": task, **extra})
        return out

    found = {}
    for steer in ("robustness", "label"):
        records, _, _ = falsify_rounds(sampler, 3, 200, 10, "failure-tree", steer, "corner", run_round)
        found[steer] = sum(v.failed for v in verdicts(records, "corner"))
    assert found["robustness"] >= 0.9 * found["label"] and found["label"] >= 2.5 * 0.087 * 200, found


def test_elite_level_falls_to_zero_once_failures_are_common():
    assert elite_level([0.5, 0.1, 0.2, 0.3, 0.4, 0.6, 0.7, 0.8]) == pytest.approx(0.4)  # the 4th lowest
    assert elite_level([-0.1] * 5 + [0.5] * 20) == 0.0
    assert near_failures([True, False], [None, None]) == [1.0, 0.0]  # labels alone
    pull = near_failures([False] * 8, [0.5, 0.1, 0.2, 0.3, 0.4, 0.6, 0.7, 0.8])
    assert pull[4] == pytest.approx(math.exp(-4)) and pull[1] > pull[2] > pull[3] > pull[4] and pull[0] == 0.0


def test_episode_verdict_reads_the_task_record():
    record = {"outcome": "handed_over", "task": task_record("fail:dropped", {"goal": -0.2, "fail:dropped": -0.01,
                                                                         "fail:arm on table": 0.0116})}
    assert episode_verdict(record, None).failed and episode_verdict(record, None).robustness == -0.2
    assert episode_verdict(record, "dropped").failed
    table = episode_verdict(record, "arm on table")
    assert not table.failed and table.robustness == 0.0116 and table.label == "fail:dropped" and table.from_task
    assert episode_verdict(record, "goal").robustness == -0.2
    with pytest.raises(PrscError, match="its failure labels: arm on table, dropped"):
        episode_verdict(record, "tipped")
    plain = {"outcome": "no_path"}
    assert episode_verdict(plain, None).failed and episode_verdict(plain, None).robustness is None
    with pytest.raises(PrscError, match="states no task"):
        episode_verdict(plain, "dropped")


def test_zero_failures_give_the_exact_binomial_bound_never_zero():
    est = failure_estimate([False] * 60, [1.0] * 60, [True] * 60)
    assert est.value == 0.0 and est.low == 0.0
    assert est.upper == pytest.approx(1 - 0.05 ** (1 / 60)) == pytest.approx(0.0487, abs=1e-4)  # rule of three: 0.05
    assert est.high == pytest.approx(1 - 0.025 ** (1 / 60))  # two-sided 95 %
    every = failure_estimate([True] * 60, [1.0] * 60, [True] * 60)
    assert every.high == 1.0 and every.low == pytest.approx(0.025 ** (1 / 60))
    some = failure_estimate([True] * 6 + [False] * 54, [1.0] * 60, [True] * 60)
    assert (some.low, some.high) == pytest.approx(clopper_pearson(6, 60)[:2]) and some.basis.startswith("exact")
    # Weighted, no failure: the exact bound on the 38 scenes drawn from the spec's law.
    spec = [True] * 20 + [k % 10 == 0 for k in range(180)]
    weights = [1.0] * 20 + [0.5] * 180
    none = failure_estimate([False] * 200, weights, spec)
    assert none.high == pytest.approx(1 - 0.025 ** (1 / 38)) and none.spec_draws == 38
    # Weighted, one failure of tiny weight: never a tighter bound than no failure at all shows.
    one = failure_estimate([k == 50 for k in range(200)], [1.0] * 20 + [1e-4] * 180, spec)
    assert one.high >= 0.9 * none.high and one.low < one.value
    allfail = failure_estimate([True] * 200, weights, spec)
    assert allfail.high == 1.0 and allfail.low == pytest.approx(0.025 ** (1 / 38))


def test_clopper_pearson_covers_where_the_normal_interval_does_not():
    # Exact coverage by the binomial law at n = 60: Clopper-Pearson holds 95 % at every p, the
    # normal interval (the old report: [0, 0] at 0 failures) does not at small p.
    n, k = 60, np.arange(61)
    bounds = [clopper_pearson(float(x), n) for x in k]
    for p in (0.001, 0.01, 0.03, 0.1, 0.5, 0.9, 0.99):
        pmf = binom.pmf(k, n, p)
        exact = sum(m for m, (lo, hi, _) in zip(pmf, bounds) if lo <= p <= hi)
        half = 1.96 * np.sqrt(k / n * (1 - k / n) / n)
        normal = sum(m for m, x, h in zip(pmf, k / n, half) if x - h <= p <= x + h)
        assert exact >= 0.95, (p, exact)
        if p in (0.001, 0.01):
            assert normal < 0.6, (p, normal)
