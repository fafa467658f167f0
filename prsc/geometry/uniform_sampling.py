"""Exact uniform sampling (no rejection, no Markov chain) from convex regions and unions
of disjoint convex pieces.

A region is decomposed once into simplices of its intrinsic dimension k (tetrahedra,
triangles, segments or one point; see triangulation.py), lifted to world coordinates. A
draw picks a simplex with probability proportional to its measure, then a uniform point
in it: barycentric weights = spacings of k sorted uniforms (a flat Dirichlet).

Each draw consumes exactly k + 1 uniforms from the caller's Generator (row-major
(n, k+1) for a batch), so `sample(rng, n)` and n calls of `sample_one(rng)` read the same
random stream.
"""

from __future__ import annotations

from bisect import bisect_right
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from prsc.geometry.affine import TOL, AffineRegion, explicit_reduction, reduce_affine
from prsc.geometry.exceptions import EmptyRegionError, UnboundedRegionError
from prsc.geometry.polytope import Polytope
from prsc.geometry.triangulation import BOUND, decompose, simplex_measures

# Pieces whose measure is below this fraction of the total are rounding slivers.
SLIVER = 1e-12
# Regions thinner than this (metres, measure / diameter^(k-1)) go through the full
# LP-based affine reduction, which decides whether they are flat.
THICK = 1e-7


@dataclass(frozen=True, eq=False)
class UniformSampler:
    """A prepared exact uniform sampler over disjoint simplices (K, k+1, n) of one dimension k."""

    simplices: NDArray[np.float64]
    measures: NDArray[np.float64]
    dim: int = field(init=False)
    cumulative: NDArray[np.float64] = field(init=False, repr=False)
    _cum_list: list[float] = field(init=False, repr=False)
    _simplex_list: list[NDArray[np.float64]] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        s = np.ascontiguousarray(self.simplices, dtype=float)
        if s.ndim != 3 or s.shape[0] == 0:
            raise EmptyRegionError("the region has no interior (no simplices)")
        w = np.asarray(self.measures, dtype=float).reshape(-1)
        if w.shape[0] != s.shape[0]:
            raise ValueError(f"{w.shape[0]} measures for {s.shape[0]} simplices")
        total = float(w.sum())
        keep = w > SLIVER * total
        if not total > 0.0 or not keep.any():
            raise EmptyRegionError("the region has measure zero")
        s, w = s[keep], w[keep]
        cum = np.cumsum(w)
        for name, value in (
            ("simplices", s), ("measures", w), ("dim", s.shape[1] - 1), ("cumulative", cum),
            ("_cum_list", cum.tolist()), ("_simplex_list", list(s)),
        ):
            object.__setattr__(self, name, value)

    @classmethod
    def from_simplices(cls, simplices: NDArray[np.float64], measures: NDArray[np.float64] | None = None) -> UniformSampler:
        """Build from world-coordinate simplices (K, k+1, n); raises EmptyRegionError if K = 0."""
        s = np.asarray(simplices, dtype=float)
        if s.ndim != 3 or s.shape[0] == 0:
            raise EmptyRegionError("the region has no interior (no simplices)")
        return cls(s, simplex_measures(s) if measures is None else measures)

    @property
    def measure(self) -> float:
        """Length, area or volume of the region (1 for a point)."""
        return float(self.cumulative[-1])

    @property
    def ambient_dim(self) -> int:
        """Dimension of the sampled points."""
        return int(self.simplices.shape[2])

    def vertices(self) -> NDArray[np.float64]:
        """All simplex vertices (with repeats), e.g. for a bounding box."""
        return self.simplices.reshape(-1, self.simplices.shape[2])

    def bounds(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Axis-aligned bounding box (lo, hi) of the region."""
        v = self.vertices()
        return v.min(axis=0), v.max(axis=0)

    def sample(self, rng: np.random.Generator, n: int) -> NDArray[np.float64]:
        """n independent uniform points, shape (n, ambient_dim)."""
        return self.points(rng.random((n, self.dim + 1)))

    def points(self, u: NDArray[np.float64]) -> NDArray[np.float64]:
        """The points of uniforms u, shape (n, dim + 1): u[:, 0] picks the simplex, the rest the point in it.

        Elementwise arithmetic only, so each point depends on its own row of u alone (the batched sampler's draws)."""
        k = self.dim
        n = u.shape[0]
        idx = np.searchsorted(self.cumulative, u[:, 0] * self.cumulative[-1], side="right")
        np.minimum(idx, len(self.cumulative) - 1, out=idx)
        verts = np.take(self.simplices, idx, axis=0)  # (n, k+1, d)
        if k == 0:
            return verts[:, 0, :]
        lam = np.empty((n, k + 1))
        if k == 1:
            lam[:, 0] = lam[:, 1] = u[:, 1]
        else:
            # Sorted cuts by a compare-exchange network (much faster than np.sort on rows).
            lo, hi = np.minimum(u[:, 1], u[:, 2]), np.maximum(u[:, 1], u[:, 2])
            if k == 3:
                z = u[:, 3]
                top = np.maximum(hi, z)
                hi = np.minimum(hi, z)
                lo, hi = np.minimum(lo, hi), np.maximum(lo, hi)
                lam[:, 3] = top
                lam[:, 2] = top - hi
            else:
                lam[:, 2] = hi
            lam[:, 1] = hi - lo
            lam[:, 0] = lo
        lam[:, k] = 1.0 - lam[:, k]
        # v0 + sum_j lam_j (v_j - v0): a coordinate that is the same at every vertex (z on a
        # table's top) comes out exactly, as a constant, not rounded differently per point.
        out = verts[:, 0, :].copy()
        for j in range(1, k + 1):
            out += lam[:, j:j + 1] * (verts[:, j, :] - verts[:, 0, :])
        return out

    def sample_one(self, rng: np.random.Generator) -> NDArray[np.float64]:
        """One uniform point (ambient_dim,); the same stream use as sample(rng, 1)."""
        k = self.dim
        u = rng.random(k + 1).tolist()
        i = min(bisect_right(self._cum_list, u[0] * self._cum_list[-1]), len(self._cum_list) - 1)
        verts = self._simplex_list[i]
        if k == 0:
            return verts[0].copy()
        # Plain floats for the weights (numpy's per-call cost dominates at this size).
        cuts = sorted(u[1:])
        lam = [cuts[0]] + [cuts[j] - cuts[j - 1] for j in range(1, k)] + [1.0 - cuts[-1]]
        return np.dot(lam, verts)


def simplices_of(region: AffineRegion, bound: float = BOUND) -> NDArray[np.float64]:
    """World-coordinate simplices (K, k+1, n) of a reduced region (empty array if flat)."""
    s_t, _ = decompose(region.A, region.b, region.center, bound)
    return region.origin + s_t @ region.basis.T


def _fast_simplices(
    poly: Polytope, tol: float, bound: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """Simplices without any LP when the explicit reduction is clearly full-dimensional.

    Vertex enumeration needs no interior point, so the Chebyshev LP (the slowest step) is
    only needed when the set is empty, unbounded or thinner than THICK, where the full
    reduction (implicit equalities, exact emptiness margin) decides. None means: use it.
    """
    try:
        origin, basis, at, bt = explicit_reduction(poly, tol)
        k = basis.shape[1]
        if k == 0:
            return None
        s_t, v = decompose(at, bt, -origin @ basis, bound)
    except (EmptyRegionError, UnboundedRegionError):
        return None
    if s_t.shape[0] == 0:
        return None
    measures = simplex_measures(s_t)
    measure = float(measures.sum())
    diameter = float(np.max(np.linalg.norm(v - v[0], axis=1))) if k > 1 else 1.0
    if not measure > THICK * diameter ** (k - 1):
        return None  # thinner than THICK (measure / diameter^(k-1) ~ thickness)
    return origin + s_t @ basis.T, measures


def prepare_sampler(poly: Polytope, tol: float = TOL, bound: float = BOUND) -> UniformSampler:
    """Exact uniform sampler for a convex polytope (any dimension 0-3 after reduction).

    Raises EmptyRegionError (empty within tol) or UnboundedRegionError.
    """
    fast = _fast_simplices(poly, tol, bound)
    if fast is not None:
        return UniformSampler(*fast)
    return UniformSampler.from_simplices(simplices_of(reduce_affine(poly, tol), bound))


def union_sampler(pieces: Sequence[UniformSampler]) -> UniformSampler:
    """Sampler over the union of disjoint pieces of the same dimension (measure-weighted)."""
    if not pieces:
        raise EmptyRegionError("no pieces")
    dims = {p.dim for p in pieces}
    if len(dims) != 1:
        raise ValueError(f"pieces of mixed dimensions {sorted(dims)}")
    return UniformSampler.from_simplices(
        np.concatenate([p.simplices for p in pieces]), np.concatenate([p.measures for p in pieces])
    )
