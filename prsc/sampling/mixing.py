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
    """(KS statistic, p-value) per column of two samples (rows are scenes); constant columns give (0, 1)."""
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
