"""How far one law's scenes are from another's: per-coordinate two-sample KS tests on object
positions (the distance `prsc bench` reports and the mixing measurement in docs/sampling.md)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy.stats import ks_2samp

from prsc.sampling.engine import SceneResult


@dataclass(frozen=True)
class Distance:
    """The largest per-coordinate KS statistic, the smallest p-value, and where it was."""

    statistic: float
    pvalue: float
    coordinate: str


def coordinates(result: SceneResult, names: Sequence[str] | None = None, relative_to: str | None = None) -> np.ndarray:
    """x, y, z of the named objects (all when None), optionally relative to one object's position."""
    by_name = {o.name: o.position for o in result.objects}
    base = by_name[relative_to] if relative_to is not None else 0.0
    chosen = names if names is not None else [o.name for o in result.objects]
    return np.concatenate([np.asarray(by_name[n], dtype=float) - base for n in chosen])


def coordinate_labels(names: Sequence[str]) -> list[str]:
    """Labels of the columns `coordinates` returns."""
    return [f"{n}.{axis}" for n in names for axis in "xyz"]


def ks_per_coordinate(a: np.ndarray, b: np.ndarray) -> list[tuple[float, float]]:
    """(KS statistic, p-value) per column of two samples (rows are scenes); constant columns give (0, 1).

    Coordinates are compared to 1e-12 m: below that they differ only by how a sampler rounds
    (a tray's z on a table top is 0.814482 from one sampler and 0.8144820000000002 from another)."""
    a, b = np.round(a, 12), np.round(b, 12)
    out = []
    for c in range(a.shape[1]):
        if np.ptp(a[:, c]) == 0 and np.ptp(b[:, c]) == 0 and a[0, c] == b[0, c]:
            out.append((0.0, 1.0))  # a fixed coordinate (z on a plane, a static object)
            continue
        test = ks_2samp(a[:, c], b[:, c])
        out.append((float(test.statistic), float(test.pvalue)))
    return out


def distance(a: np.ndarray, b: np.ndarray, labels: Sequence[str]) -> Distance:
    """The worst coordinate of `ks_per_coordinate` (largest statistic)."""
    tests = ks_per_coordinate(a, b)
    worst = max(range(len(tests)), key=lambda c: tests[c][0])
    return Distance(tests[worst][0], min(p for _, p in tests), labels[worst])


def sweep_diagnostic(
    path: str, sweeps: Sequence[int], n: int, seed: int = 0, names: Sequence[str] | None = None,
    relative_to: str | None = None, reference: bool = True,
) -> list[dict[str, float]]:
    """Per number of sweeps s: the largest |correlation| across n scenes between a coordinate
    of the sequential start and the same coordinate after s sweeps (same seed: the chain
    with s sweeps is a prefix of the chain with more), and, with `reference`, the KS
    distance to the rejection reference (seed + 1)."""
    from prsc.sampling import compile_sampler

    def draw(law: str, s: int, seed: int) -> np.ndarray:
        sampler = compile_sampler(path, law=law, sweeps=max(s, 1))
        return np.array([coordinates(sampler.sample(seed, i), names, relative_to) for i in range(n)])

    start = draw("sequential", 0, seed)
    moving = np.ptp(start, axis=0) > 0
    ref = draw("rejection", 0, seed + 1) if reference else None
    rows = []
    for s in sweeps:
        x = start if s == 0 else draw("joint", s, seed)
        corr = [abs(np.corrcoef(start[:, c], x[:, c])[0, 1]) for c in np.nonzero(moving)[0]]
        row = {"sweeps": float(s), "start_correlation": float(max(corr))}
        if ref is not None:
            tests = ks_per_coordinate(x[:, moving], ref[:, moving])
            row["ks_statistic"] = max(d for d, _ in tests)
            row["ks_pvalue"] = min(p for _, p in tests)
        rows.append(row)
    return rows


if __name__ == "__main__":  # python -m prsc.sampling.mixing SPEC N [relative_to] [--no-reference]
    import sys

    argv = [a for a in sys.argv[1:] if a != "--no-reference"]
    for row in sweep_diagnostic(argv[0], (0, 1, 2, 4, 8), int(argv[1]), relative_to=argv[2] if len(argv) > 2 else None,
                                reference="--no-reference" not in sys.argv):
        print("  ".join(f"{k} {v:.4g}" for k, v in row.items()), flush=True)
