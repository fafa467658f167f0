"""The packed bin beside an arm (specs/bin_ten_parts_arm.prs) and the plan's choice between candidate
rounds and Gibbs rounds (prsc/sampling/sampler_plan.py, path_costs.py; docs/sampling.md, "Which path").

- The parts lie `completely in` the bin and no taller than its walls, so they meet the Panda's box only
  where the bin does, which the bin's own test excludes: the group's law does not depend on where the
  bin stands, and the spec takes Gibbs rounds (before: the scalar sweeps, about 20 scenes per CPU-second).
- The law: the parts relative to the bin follow the same law as in specs/bin_ten_parts.prs (the same bin
  and parts; where the bin stands does not change their law), so the stored rejection reference of
  that spec is the reference here: per-coordinate KS p >= 0.01 at 500 scenes, as
  tests/sampling/test_packed_bin.py checks it (and where the sequential law fails the same test).
- The plan weighs what a scene costs on either path where both can draw a spec: bin_picking, where
  candidates pass often enough and cost about 2x Gibbs rounds, keeps its exact candidate rounds.
"""

from __future__ import annotations

import numpy as np

from prsc.cli import main
from prsc.ir import compile_program
from prsc.sampling import Sampler, compile_sampler
from prsc.sampling.candidates import Pilot
from prsc.sampling.mixing import ks_per_coordinate
from prsc.sampling.path_costs import EXACT_PREMIUM, path_costs
from tests.sampling.packed_bin_reference import LABELS, REPO, coordinates, load
from tests.sampling.scene_checks import check_scenes

ARM = REPO / "specs" / "bin_ten_parts_arm.prs"
P_MIN = 0.01
TESTED = [j for j, label in enumerate(LABELS) if label.split(".")[0] in ("washer_0", "washer_4", "bolt_0", "bolt_4")]


def test_the_bin_beside_the_arm_takes_gibbs_rounds_and_says_why():
    plan = compile_sampler(ARM).plan
    assert plan.path == "Gibbs rounds", plan.why
    assert "lie in bin_1's box, whose tests against robot decide for them" in plan.describe()


def test_explain_prints_why_the_bin_beside_the_arm_takes_gibbs_rounds(capsys):
    assert main(["explain", str(ARM)]) == 0  # its third line is the plan's path and why (Sampler.plan.describe)
    path = next(line for line in capsys.readouterr().out.splitlines() if line.startswith("path: "))
    assert path.startswith("path: Gibbs rounds (") and "lie in bin_1's box, whose tests against robot decide for them" in path


def test_a_spec_whose_candidates_pass_keeps_candidate_rounds_and_explain_gives_the_costs(capsys):
    plan = compile_sampler(REPO / "specs" / "bin_picking.prs").plan
    assert plan.path == "candidate rounds", plan.why
    assert "box draws by candidates against" in plan.why  # Gibbs rounds could draw it: the costs were weighed
    assert compile_sampler(REPO / "specs" / "shelf_bin.prs").plan.path == "candidate rounds"
    assert main(["explain", str(REPO / "specs" / "bin_picking.prs")]) == 0
    assert "path: candidate rounds" in capsys.readouterr().out


def test_the_costs_weigh_the_scenes_no_candidate_passes():
    cheap = path_costs(Pilot(scenes=8, passed=8, drawn=8 * 20, size=468), objects=12, gibbs_rows=8 * 1200, gibbs_scenes=8)
    assert cheap.candidates == 12 * 20 and not cheap.gibbs_pays  # 240 box draws against 3,000
    # Half the pilot passes within the budget: candidate rounds pass the old test, but the other half spends
    # the budget and then the scalar sweeps.
    costly = path_costs(Pilot(scenes=8, passed=4, drawn=4 * 300 + 4 * 468, size=468), objects=12, gibbs_rows=8 * 1200,
                        gibbs_scenes=8)
    assert costly.gibbs_pays and costly.candidates > EXACT_PREMIUM * costly.gibbs
    # Pilots in which Gibbs rounds drew no proposal (one object with a random mass) weigh nothing: candidate
    # rounds stay, and the reason reads (it divided by zero, an internal error of `prsc compile`).
    none = path_costs(Pilot(scenes=8, passed=8, drawn=8, size=468), objects=1, gibbs_rows=0, gibbs_scenes=8)
    assert not none.gibbs_pays and "Gibbs rounds drew no proposal" in none.describe()


def test_the_parts_beside_the_arm_follow_the_rejection_reference_and_hold_the_spec():
    sampler = compile_sampler(ARM)
    results = sampler.results(202, range(500))
    pvalues = [p for _, p in ks_per_coordinate(np.array([coordinates(r) for r in results])[:, TESTED], load()[:, TESTED])]
    assert len(pvalues) == 14 and min(pvalues) >= P_MIN, dict(zip([LABELS[j] for j in TESTED], np.round(pvalues, 4)))
    program = compile_program(str(ARM))
    scenes = Sampler(program, "exact").batch(7, range(40))
    report = check_scenes(program, iter(scenes))  # no part meets the arm's box, the bin, or another part
    assert not report and report.checked >= 40 * len(program.objects), report
    assert sampler.scene(7, 33) == scenes[33] and sampler.batch(7, [12, 5]) == [scenes[12], scenes[5]]
