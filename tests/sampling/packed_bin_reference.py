"""The exact reference of the packed-bin law test, stored as data: coordinates of 4,000 scenes
of specs/bin_ten_parts.prs drawn by whole-scene rejection, which only the law's own code can change.

    python -m tests.sampling.packed_bin_reference     # rewrites data/packed_bin_reference.npz (minutes)

Whole-scene rejection one scene at a time (`--law rejection`) would need about 7,000 scenes
drawn per kept one; the candidate sampler (prsc/sampling/candidates.py) is the same
rejection vectorised over candidates (each scene keeps its first passing candidate), so the
reference is drawn by it with the budget of candidates per scene lifted. Stored as uint16 over
each coordinate's range (a step of at most 6 micrometres or 0.006 degrees), about 240 KB.
tests/sampling/test_packed_bin.py checks that the first stored rows are still what it draws.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from prsc.sampling import compile_sampler
from prsc.sampling.candidate_plan import candidate_plan
from prsc.sampling.candidates import CandidateSampler
from prsc.sampling.engine import SceneResult

REPO = Path(__file__).resolve().parents[2]
SPEC = REPO / "specs" / "bin_ten_parts.prs"
REFERENCE = Path(__file__).parent / "data" / "packed_bin_reference.npz"
SEED = 303
N = 4000
BUDGET = 400_000  # candidates a reference scene may draw: none has needed a tenth of it
WASHERS = [f"washer_{i}" for i in range(5)]
BOLTS = [f"bolt_{i}" for i in range(5)]
LABELS = [f"{w}.{c}" for w in WASHERS for c in ("x", "y", "diameter", "yaw")] + \
    [f"{b}.{c}" for b in BOLTS for c in ("x", "y", "height")]


def coordinates(result: SceneResult) -> np.ndarray:
    """Per part: its centre's x and y relative to the bin, a washer's diameter and yaw (degrees modulo 90,
    its box's symmetry) or a bolt's height."""
    at = {o.name: o for o in result.objects}
    base = at["bin_1"].position
    row: list[float] = []
    for name in WASHERS:
        o = at[name]
        yaw = np.degrees(np.arctan2(o.rotation[1, 0], o.rotation[0, 0])) % 90.0
        row += [*(o.position - base)[:2], o.dims[0], yaw]
    for name in BOLTS:
        o = at[name]
        row += [*(o.position - base)[:2], o.dims[2]]
    return np.array(row)


def rejection_scenes(seed: int, indices: range) -> np.ndarray:
    """Coordinates of scenes `indices` by whole-scene rejection (candidate rounds without a budget)."""
    from prsc.sampling import candidates

    sampler = compile_sampler(SPEC)
    drawer = CandidateSampler(candidate_plan(sampler.constraints, sampler.runtimes), sampler.constraints, sampler.runtimes)
    budget, candidates.BUDGET = candidates.BUDGET, BUDGET
    try:
        drawn = drawer.draw(seed, indices)
    finally:
        candidates.BUDGET = budget
    assert all(isinstance(d, SceneResult) for d in drawn), "a reference scene found no passing candidate"
    return np.array([coordinates(d) for d in drawn])  # type: ignore[arg-type]


def load() -> np.ndarray:
    """The stored reference, as coordinates (N, len(LABELS))."""
    stored = np.load(REFERENCE)
    return stored["lo"] + stored["codes"].astype(float) * stored["step"]


def main() -> None:
    """Draw the reference and write it."""
    rows = np.vstack([rejection_scenes(SEED, range(start, min(start + 250, N))) for start in range(0, N, 250)])
    lo, hi = rows.min(axis=0), rows.max(axis=0)
    step = np.where(hi > lo, (hi - lo) / 65535.0, 1.0)
    codes = np.round((rows - lo) / step).astype(np.uint16)
    np.savez_compressed(REFERENCE, codes=codes, lo=lo, step=step, labels=np.array(LABELS))


if __name__ == "__main__":
    main()
