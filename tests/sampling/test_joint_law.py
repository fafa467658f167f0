"""The default law is the joint one (docs/sampling.md, "The joint law"): per-coordinate
two-sample KS tests at fixed seeds against the exact reference (whole-scene rejection,
`--law rejection`), and the same test fails for the sequential law, so it can fail.

Two dense specs where the laws differ: three cups sharing one y beside a block (the shape
of the original cupPour) and four cubes on a tray (cube positions relative to the tray).
Each law's scenes are drawn in a worker process of their own, side by side.
"""

from __future__ import annotations

import json
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

import numpy as np
import pytest

from prsc.cli import main
from prsc.errors import PrscError
from prsc.sampling import compile_sampler
from prsc.sampling.mixing import coordinates, ks_per_coordinate
from prsc.sampling.proposal import Proposal

DATA = Path(__file__).parent / "data"
P_MIN = 0.01  # every coordinate of the default law: KS p >= P_MIN; the sequential law: some p < P_MIN
N = 2000  # scenes per law and spec
CHUNKS = 4  # each law's scenes are drawn in index chunks, spread over the two workers
SEEDS = {"rejection": 101, "joint": 202, "sequential": 202}
SPECS = {
    "aligned_cups": (("cup_1", "cup_2", "cup_3"), None),
    "tray_four_cubes": (("c1", "c2", "c3", "c4"), "tray"),
}


def _planar(spec: str, law: str, start: int) -> np.ndarray:
    """x and y of the spec's objects in scenes start .. start + N/CHUNKS - 1 of one law (z is fixed by `on`)."""
    names, relative_to = SPECS[spec]
    sampler = compile_sampler(DATA / f"{spec}.prs", law=law)
    n = N // CHUNKS
    rows = [coordinates(sampler.sample(SEEDS[law], i), names, relative_to) for i in range(start, start + n)]
    return np.array(rows).reshape(n, len(names), 3)[:, :, :2].reshape(n, -1)


@pytest.fixture(scope="module")
def samples() -> dict[tuple[str, str], np.ndarray]:
    jobs = [(spec, law, c * (N // CHUNKS)) for spec in SPECS for law in SEEDS for c in range(CHUNKS)]
    with ProcessPoolExecutor(max_workers=2, mp_context=get_context("fork")) as pool:
        parts = list(pool.map(_planar, *zip(*jobs)))
    return {(spec, law): np.vstack([p for (s, w, _), p in zip(jobs, parts) if (s, w) == (spec, law)])
            for spec in SPECS for law in SEEDS}


@pytest.mark.parametrize("spec", sorted(SPECS))
def test_the_default_law_matches_the_rejection_reference(samples, spec):
    pvalues = [p for _, p in ks_per_coordinate(samples[spec, "joint"], samples[spec, "rejection"])]
    assert min(pvalues) >= P_MIN, np.round(pvalues, 4)


@pytest.mark.parametrize("spec", sorted(SPECS))
def test_the_sequential_law_fails_the_same_test(samples, spec):
    pvalues = [p for _, p in ks_per_coordinate(samples[spec, "sequential"], samples[spec, "rejection"])]
    assert min(pvalues) < P_MIN, np.round(pvalues, 4)


def test_the_default_law_is_the_joint_one_and_joint_spells_rejection():
    spec = DATA / "aligned_cups.prs"
    assert compile_sampler(spec).law == "joint"
    assert compile_sampler(spec, joint=True).law == "rejection"
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
