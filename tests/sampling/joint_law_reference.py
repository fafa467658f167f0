"""The exact reference of the joint-law tests, stored as data: planar coordinates of scenes
of whole-scene rejection (`--law rejection`), which only the law's own code can change.

    python -m tests.sampling.joint_law_reference     # rewrites data/joint_law_reference.npz

tests/sampling/test_joint_law.py checks that the stored rows are still what the sampler
draws (the first scenes of each spec, drawn again), so a change of the law or the stream
makes that test fail until the file is written again.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from prsc.sampling import compile_sampler
from prsc.sampling.mixing import coordinates

DATA = Path(__file__).parent / "data"
REFERENCE = DATA / "joint_law_reference.npz"
SEED = 101
N = 4000  # scenes per spec: twice the laws under test, so the reference adds little noise
SPECS = {
    "aligned_cups": (("cup_1", "cup_2", "cup_3"), None),
    "tray_four_cubes": (("c1", "c2", "c3", "c4"), "tray"),
}


def planar(spec: str, law: str, seed: int, indices: range) -> np.ndarray:
    """x and y of the spec's objects (z is fixed by `on`) in scenes `indices` of one law and seed
    (law "gibbs": the joint law by Gibbs sweeps alone, without candidate rounds)."""
    names, relative_to = SPECS[spec]
    if law == "gibbs":
        sampler = compile_sampler(DATA / f"{spec}.prs", law="joint", batched=False)
    else:
        sampler = compile_sampler(DATA / f"{spec}.prs", law=law)
    rows = [coordinates(sampler.sample(seed, i), names, relative_to) for i in indices]
    return np.array(rows).reshape(len(indices), len(names), 3)[:, :, :2].reshape(len(indices), -1)


def main() -> None:
    """Draw the reference of every spec and write it."""
    np.savez_compressed(REFERENCE, **{spec: planar(spec, "rejection", SEED, range(N)).astype(np.float32) for spec in SPECS})


if __name__ == "__main__":
    main()
