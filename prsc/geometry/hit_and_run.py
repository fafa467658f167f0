"""Hit-and-run sampling (the ProbRobScene paper's Algorithm 1), kept for comparison with
the exact sampler.

From a point x inside the region: draw a uniform random direction d, find the chord
{x + m d} inside the region, move to a uniform point on it; repeat. The chain's law
tends to the uniform one, but only after a walk of 75 (a plain rotated box) to more than
500 (a thin slab) steps per independent sample. The walk runs in the region's reduced
coordinates (affine.py): a region on a surface has no 3D interior, and a 3D walk from its
Chebyshev centre would never move.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prsc.geometry.affine import TOL, AffineRegion, reduce_affine
from prsc.geometry.exceptions import UnboundedRegionError
from prsc.geometry.polytope import Polytope


def hit_and_run_step(
    a: NDArray[np.float64], b: NDArray[np.float64], x: NDArray[np.float64], rng: np.random.Generator
) -> NDArray[np.float64]:
    """One hit-and-run move of each chain x (n, k) inside {a t <= b}."""
    n, k = x.shape
    d = rng.standard_normal((n, k))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    ad = d @ a.T  # (n, m)
    slack = np.maximum(b - x @ a.T, 0.0)  # rounding can push x a hair outside
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = slack / ad
    hi = np.min(np.where(ad > 0, ratio, np.inf), axis=1)
    lo = np.max(np.where(ad < 0, ratio, -np.inf), axis=1)
    if not (np.all(np.isfinite(hi)) and np.all(np.isfinite(lo))):
        raise UnboundedRegionError("hit-and-run needs a bounded region")
    m = lo + (hi - lo) * rng.random(n)
    return x + m[:, None] * d


def hit_and_run(
    region: Polytope | AffineRegion,
    rng: np.random.Generator,
    n: int,
    walk_length: int = 100,
    start: ArrayLike | None = None,
    independent: bool = True,
    tol: float = TOL,
) -> NDArray[np.float64]:
    """n points (n, ambient) by hit-and-run from the Chebyshev centre (or `start`).

    independent=True runs n chains side by side (vectorised), each for walk_length steps;
    independent=False runs one chain and keeps every walk_length-th state (the paper's use).
    """
    reg = region if isinstance(region, AffineRegion) else reduce_affine(region, tol)
    k = reg.dim
    if k == 0:
        return np.repeat(reg.origin[None, :], n, axis=0)
    x0 = reg.center if start is None else reg.project(start)
    if independent:
        x = np.repeat(np.asarray(x0, dtype=float)[None, :], n, axis=0)
        for _ in range(walk_length):
            x = hit_and_run_step(reg.A, reg.b, x, rng)
        return reg.lift(x)
    x = np.asarray(x0, dtype=float)[None, :]
    out = np.empty((n, k))
    for i in range(n):
        for _ in range(walk_length):
            x = hit_and_run_step(reg.A, reg.b, x, rng)
        out[i] = x[0]
    return reg.lift(out)
