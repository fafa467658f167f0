"""The default law is the joint one (docs/sampling.md, "The joint law"): per-coordinate
two-sample KS tests at fixed seeds against the exact reference (whole-scene rejection,
`--law rejection`), and the same test fails for the sequential law, so it can fail.

Two dense specs where the laws differ: three cups sharing one y beside a block (the shape
of the original cupPour) and four cubes on a tray (cube positions relative to the tray).
The reference is stored as data (tests/sampling/joint_law_reference.py: 4,000 rejection
scenes per spec), checked against fresh draws; each law under test draws N scenes here.

Power: with N = 500 against 4,000, a per-coordinate KS test at p < 0.01 detects a shift
of the CDF by 0.08; the sequential law, at the same N, gives p = 2e-21 (cups) and 3e-4
(tray) (the companion test). The default law draws both by candidate rounds
(prsc/sampling/candidates.py); the Gibbs sweeps it falls back to are tested alone on the cups.
"""

from __future__ import annotations

import json
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context

import numpy as np
import pytest

from prsc.cli import main
from prsc.errors import PrscError
from prsc.sampling import compile_sampler
from prsc.sampling.mixing import ks_per_coordinate
from prsc.sampling.proposal import Proposal
from tests.sampling.joint_law_reference import DATA, REFERENCE, SPECS, planar
from tests.sampling.joint_law_reference import SEED as REFERENCE_SEED

P_MIN = 0.01  # every coordinate of the default law: KS p >= P_MIN; the sequential law: some p < P_MIN
N = 500  # scenes per law under test and spec
CHUNKS = 2  # each law's scenes are drawn in index chunks, spread over two worker processes
SEEDS = {"joint": 202, "sequential": 202, "gibbs": 202}
# The default law draws both specs by candidate rounds; the Gibbs sweeps it falls back to are
# tested on the cups, where the sequential law is furthest from the joint one.
LAWS_OF = {"aligned_cups": ("joint", "sequential", "gibbs"), "tray_four_cubes": ("joint", "sequential")}


def _chunk(spec: str, law: str, start: int) -> np.ndarray:
    return planar(spec, law, SEEDS[law], range(start, start + N // CHUNKS))


@pytest.fixture(scope="module")
def reference() -> dict[str, np.ndarray]:
    stored = np.load(REFERENCE)
    return {spec: stored[spec].astype(float) for spec in SPECS}


@pytest.fixture(scope="module")
def samples() -> dict[tuple[str, str], np.ndarray]:
    jobs = [(spec, law, c * (N // CHUNKS)) for spec in SPECS for law in LAWS_OF[spec] for c in range(CHUNKS)]
    with ProcessPoolExecutor(max_workers=2, mp_context=get_context("fork")) as pool:
        parts = list(pool.map(_chunk, *zip(*jobs)))
    return {(spec, law): np.vstack([p for (s, w, _), p in zip(jobs, parts) if (s, w) == (spec, law)])
            for spec in SPECS for law in LAWS_OF[spec]}


@pytest.mark.parametrize("spec", sorted(SPECS))
def test_the_stored_reference_is_what_rejection_draws(reference, spec):
    """The data file is the sampler's: its first scenes drawn again match to float32 precision."""
    fresh = planar(spec, "rejection", REFERENCE_SEED, range(20))
    assert reference[spec].shape[0] >= 4 * N
    np.testing.assert_allclose(reference[spec][:20], fresh, atol=1e-6)


@pytest.mark.parametrize("spec", sorted(SPECS))
def test_the_default_law_matches_the_rejection_reference(samples, reference, spec):
    pvalues = [p for _, p in ks_per_coordinate(samples[spec, "joint"], reference[spec])]
    assert min(pvalues) >= P_MIN, np.round(pvalues, 4)


def test_the_gibbs_sweeps_alone_match_the_rejection_reference(samples, reference):
    pvalues = [p for _, p in ks_per_coordinate(samples["aligned_cups", "gibbs"], reference["aligned_cups"])]
    assert min(pvalues) >= P_MIN, np.round(pvalues, 4)


@pytest.mark.parametrize("spec", sorted(SPECS))
def test_the_sequential_law_fails_the_same_test(samples, reference, spec):
    pvalues = [p for _, p in ks_per_coordinate(samples[spec, "sequential"], reference[spec])]
    assert min(pvalues) < P_MIN, np.round(pvalues, 4)


def test_the_default_law_is_the_joint_one():
    spec = DATA / "aligned_cups.prs"
    assert compile_sampler(spec).law == "joint"
    assert compile_sampler(spec, law="rejection").plan.path == "rejection"
    # Scene k is a function of (spec, seed, k): the same alone or after other scenes.
    a, b = compile_sampler(spec), compile_sampler(spec)
    for i in range(3):
        a.sample(3, i)
    first = [o.position for o in a.sample(3, 7).objects]
    again = [o.position for o in b.sample(3, 7).objects]
    assert all(np.array_equal(x, y) for x, y in zip(first, again))


def test_a_proposal_reweights_the_sequential_law_and_refuses_another(tmp_path, capsys):
    spec = DATA / "aligned_cups.prs"
    assert compile_sampler(spec, proposal=Proposal()).law == "sequential"
    with pytest.raises(PrscError, match="--proposal"):
        compile_sampler(spec, law="joint", proposal=Proposal())
    proposal = tmp_path / "proposal.json"
    proposal.write_text(json.dumps(Proposal().to_json()))
    out = tmp_path / "scenes.jsonl"
    assert main(["sample", str(spec), "-n", "2", "--proposal", str(proposal), "-o", str(out)]) == 0
    assert len(out.read_text().splitlines()) == 2
    assert main(["sample", str(spec), "-n", "2", "--law", "joint", "--proposal", str(proposal)]) == 2
    assert "--proposal" in capsys.readouterr().err
    assert main(["sample", str(spec), "-n", "1", "--joint", "--law", "sequential"]) == 2


def test_compile_keeps_the_law_in_the_folder_digest(tmp_path, capsys):
    spec = str(DATA / "aligned_cups.prs")
    out = str(tmp_path / "out")
    assert main(["compile", spec, "--target", "json", "-n", "2", "-o", out]) == 0
    assert main(["compile", spec, "--target", "json", "-n", "2", "-o", out]) == 0  # same law: up to date
    # Scenes of another law are not this folder's: refused without --force, replaced with it.
    assert main(["compile", spec, "--target", "json", "-n", "2", "-o", out, "--law", "sequential"]) == 2
    assert "--force" in capsys.readouterr().err
    assert main(["compile", spec, "--target", "json", "-n", "2", "-o", out, "--law", "sequential", "--force"]) == 0


def test_the_default_law_is_tested_on_both_of_its_samplers():
    """Both specs' default law is drawn by candidate rounds (docs/sampling.md, "Candidate rounds"),
    and the cups' also by the Gibbs sweeps alone, so the KS tests above check both samplers."""
    for spec in SPECS:
        sampler = compile_sampler(DATA / f"{spec}.prs")
        assert sampler.plan.path == "candidate rounds", sampler.plan.why
    assert compile_sampler(DATA / "aligned_cups.prs", batched=False).plan.path == "sequential + sweeps"
