"""Affine-hull reduction: write a polytope as p = origin + basis @ t, t in a full-dimensional
polytope of dimension k in {0, 1, 2, 3}.

A region on a surface (`on X`) has zero volume in 3D: its 3D Chebyshev ball has radius 0,
hit-and-run never moves and a volume-weighted sampler sees nothing. Reducing to the
affine hull first makes every region full-dimensional in its own coordinates t, where
lengths, areas and volumes are measured (the basis is orthonormal).

Equalities come from explicit rows C p = d, from opposite pairs a p <= b, -a p <= -b'
closer than `tol`, and, when the reduced Chebyshev radius is still <= tol, from an LP
that finds the rows tight on the whole set (implicit equalities).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prsc.geometry.exceptions import EmptyRegionError
from prsc.geometry.lp import chebyshev_center, solve_lp
from prsc.geometry.polytope import Polytope

# Default geometric tolerance, metres: below the spec's 1e-9 m guarantee, well above
# double rounding at scene scale (1e-16 * 10 m).
TOL = 1e-10
# A row whose projection on the subspace is shorter than this is constant there.
_FLAT_ROW = 1e-9
# Relative singular value below which equality rows are linearly dependent.
_RANK_TOL = 1e-9


@dataclass(frozen=True, eq=False)
class AffineRegion:
    """p = origin + basis @ t with t in {A t <= b}, full-dimensional in t (dim = k).

    `A` has unit rows (distances in t are metres), `labels` are the source rows' labels,
    `center`/`radius` the Chebyshev ball in t (radius 0 for a point).
    """

    origin: NDArray[np.float64]
    basis: NDArray[np.float64]
    A: NDArray[np.float64]
    b: NDArray[np.float64]
    labels: NDArray[np.int64]
    center: NDArray[np.float64]
    radius: float

    @property
    def dim(self) -> int:
        """Intrinsic dimension k (0 point, 1 segment, 2 polygon, 3 polyhedron)."""
        return int(self.basis.shape[1])

    @property
    def ambient_dim(self) -> int:
        """Dimension of the space p lives in."""
        return int(self.basis.shape[0])

    def lift(self, t: ArrayLike) -> NDArray[np.float64]:
        """Reduced coordinates (..., k) to ambient points (..., n)."""
        return self.origin + np.asarray(t, dtype=float) @ self.basis.T

    def project(self, p: ArrayLike) -> NDArray[np.float64]:
        """Ambient points (..., n) to reduced coordinates (..., k) (orthogonal projection)."""
        return (np.asarray(p, dtype=float) - self.origin) @ self.basis

    def center_point(self) -> NDArray[np.float64]:
        """The Chebyshev centre as an ambient point."""
        return self.lift(self.center)

    def reduce_rows(self, A: ArrayLike, b: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Ambient rows A p <= b in reduced coordinates: (A basis) t <= b - A origin."""
        a = np.asarray(A, dtype=float).reshape(-1, self.ambient_dim)
        return a @ self.basis, np.asarray(b, dtype=float).reshape(-1) - a @ self.origin


def _empty(message: str, labels: ArrayLike) -> EmptyRegionError:
    lab = tuple(sorted({int(x) for x in np.asarray(labels).reshape(-1) if int(x) >= 0}))
    return EmptyRegionError(message, lab)


def _subspace(
    e: NDArray[np.float64], ed: NDArray[np.float64], n: int
) -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
    """Least-squares point, orthonormal null-space basis and residual of e p = ed."""
    if e.shape[0] == 0:
        return np.zeros(n), np.eye(n), 0.0
    w, s, vt = np.linalg.svd(e, full_matrices=True)
    rank = int(np.sum(s > _RANK_TOL * max(s[0], 1.0)))
    origin = vt[:rank].T @ ((w[:, :rank].T @ ed) / s[:rank])
    residual = float(np.max(np.abs(e @ origin - ed))) if e.shape[0] else 0.0
    return origin, vt[rank:].T.copy(), residual


def _implicit_equalities(
    a: NDArray[np.float64], b: NDArray[np.float64], x: NDArray[np.float64], r: float, tol: float
) -> NDArray[np.intp]:
    """Indices of rows tight (within tol) everywhere on the nearly flat set {a t <= b}."""
    relaxed = b + max(-r, 0.0)  # makes x feasible when r is a rounding-level negative
    slack = relaxed - a @ x
    cand = np.flatnonzero(slack <= 4 * tol + 2 * abs(r))
    m, k = a.shape
    while cand.size:
        # max sum s_i, a_i t + s_i <= b_i (i candidate), 0 <= s_i <= 1: any row that can be
        # strictly slack gets s_i > 0 at the optimum of some iteration.
        nc = cand.size
        rows = np.zeros((m, k + nc))
        rows[:, :k] = a
        rows[cand, k + np.arange(nc)] = 1.0
        cost = np.concatenate([np.zeros(k), -np.ones(nc)])
        lo = np.concatenate([np.full(k, -np.inf), np.zeros(nc)])
        hi = np.concatenate([np.full(k, np.inf), np.ones(nc)])
        sol = solve_lp(cost, rows, np.full(m, -np.inf), relaxed, lo, hi)
        if sol.status != "optimal":
            break
        free = sol.x[k:] > tol
        if not free.any():
            break
        cand = cand[~free]
    return cand


@dataclass(frozen=True, eq=False)
class _Rows:
    """Normalised rows after the linear-algebra stage of the reduction."""

    a: NDArray[np.float64]  # ambient inequality rows (unit) still in play
    b: NDArray[np.float64]
    lab: NDArray[np.int64]
    e: NDArray[np.float64]  # ambient equality rows (unit)
    ed: NDArray[np.float64]
    elab: NDArray[np.int64]


def _explicit_rows(poly: Polytope, tol: float) -> _Rows:
    """Normalise, check constant rows, turn opposite pairs closer than tol into equalities."""
    an = np.sqrt(np.einsum("ij,ij->i", poly.A, poly.A))
    en = np.sqrt(np.einsum("ij,ij->i", poly.C, poly.C))
    const = an < _FLAT_ROW
    econst = en < _FLAT_ROW
    an[const] = 1.0
    en[econst] = 1.0
    a, b, lab = poly.A / an[:, None], poly.b / an, poly.labels
    e, ed, elab = poly.C / en[:, None], poly.d / en, poly.eq_labels
    if np.any(b[const] < -tol):
        raise _empty("a constant row 0 <= b < 0 is violated", lab[const & (b < -tol)])
    a, b, lab = a[~const], b[~const], lab[~const]
    if np.any(np.abs(ed[econst]) > tol):
        raise _empty("a constant equality 0 = d != 0", elab[econst])
    e, ed, elab = e[~econst], ed[~econst], elab[~econst]

    # Opposite pairs a p <= b_i, -a p <= b_j with b_i + b_j <= tol: a (numerically) thin
    # slab, i.e. an equality. Cheap to spot; saves the implicit-equality LP in the usual
    # `on` case.
    if a.shape[0] >= 2:
        g = a @ a.T
        ii, jj = np.nonzero(np.triu(g < -1.0 + 1e-12, 1))
        if ii.size:
            gap = b[ii] + b[jj]
            bad = gap < -2.0 * tol  # the same test as a Chebyshev margin < -tol
            if bad.any():
                k = int(np.argmax(bad))
                raise _empty("two parallel half-spaces do not overlap", [lab[ii[k]], lab[jj[k]]])
            thin = gap <= tol
            if thin.any():
                ii, jj = ii[thin], jj[thin]
                e = np.vstack([e, a[ii]])
                ed = np.concatenate([ed, (b[ii] - b[jj]) / 2.0])
                elab = np.concatenate([elab, lab[ii]])
                keep = np.ones(a.shape[0], dtype=bool)
                keep[ii] = False
                keep[jj] = False
                a, b, lab = a[keep], b[keep], lab[keep]
    return _Rows(a, b, lab, e, ed, elab)


def _project_rows(rows: _Rows, n: int, tol: float) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray, NDArray]:
    """origin, basis, unit reduced rows (at, bt), their labels and kept-row mask."""
    origin, basis, residual = _subspace(rows.e, rows.ed, n)
    if residual > tol:
        raise _empty("the equality constraints are inconsistent", rows.elab)
    at = rows.a @ basis
    bt = rows.b - rows.a @ origin
    norms = np.linalg.norm(at, axis=1)
    flat = norms < _FLAT_ROW
    if np.any(bt[flat] < -tol):
        raise _empty(
            "a half-space misses the constraint plane", np.concatenate([rows.lab[flat & (bt < -tol)], rows.elab])
        )
    keep = ~flat
    return origin, basis, at[keep] / norms[keep, None], bt[keep] / norms[keep], rows.lab[keep], keep


def explicit_reduction(
    poly: Polytope, tol: float = TOL
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """(origin, basis, A_t, b_t) from explicit equalities and opposite pairs only (no LP).

    The fast path of the exact sampler: in the usual case this already is the affine hull;
    callers must check the result is full-dimensional (else use reduce_affine).
    """
    origin, basis, at, bt, _, _ = _project_rows(_explicit_rows(poly, tol), poly.dim, tol)
    return origin, basis, at, bt


def reduce_affine(poly: Polytope, tol: float = TOL) -> AffineRegion:
    """Affine-hull reduction of `poly`; raises EmptyRegionError if it is empty (within tol)."""
    rows = _explicit_rows(poly, tol)
    n = poly.dim
    while True:
        origin, basis, at, bt, rl, keep = _project_rows(rows, n, tol)
        a_kept, b_kept = rows.a[keep], rows.b[keep]
        k = basis.shape[1]
        if k == 0:
            return AffineRegion(origin, basis, at.reshape(0, 0), bt[:0], rl[:0], np.zeros(0), 0.0)
        x, r = chebyshev_center(at, bt)
        if r < -tol:
            raise _empty("the constraints have no common point", np.concatenate([rows.lab, rows.elab]))
        if r > tol:
            return AffineRegion(origin, basis, at, bt, rl, x, r)
        imp = _implicit_equalities(at, bt, x, r, tol)
        if imp.size == 0:
            return AffineRegion(origin, basis, at, bt, rl, x, max(r, 0.0))
        # Move the implicit equalities (in ambient form) into the equality set and repeat
        # in the smaller subspace.
        rest = np.ones(at.shape[0], dtype=bool)
        rest[imp] = False
        rows = _Rows(
            a_kept[rest], b_kept[rest], rl[rest],
            np.vstack([rows.e, a_kept[imp]]), np.concatenate([rows.ed, b_kept[imp]]),
            np.concatenate([rows.elab, rl[imp]]),
        )
