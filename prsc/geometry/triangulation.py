"""Vertex enumeration and simplex decomposition of a full-dimensional polytope {A t <= b}
in k = 0..3 reduced coordinates (see affine.py).

Vertices are found by intersecting every k-subset of rows (Cramer's rule, vectorised) and
keeping the feasible ones: for the 6-60 rows a scene region has this is as fast as qhull
and needs no interior point. Then:
  k = 1: the segment [lo, hi];
  k = 2: vertices ordered by angle, fan of triangles from the first vertex;
  k = 3: each facet's vertices ordered by angle, fanned into triangles, each joined to the
         vertex centroid (an interior point) to form tetrahedra.
Unbounded sets are detected exactly from the rows' recession rays (`is_bounded`), and a
vertex farther than `bound` (metres) from a reference point counts as unbounded too.
"""

from __future__ import annotations

import math
from functools import lru_cache
from itertools import combinations

import numpy as np
from numpy.typing import NDArray

from prsc.geometry.exceptions import UnboundedRegionError

BOUND = 1e6
# Vertices closer than this (metres) are one vertex; a vertex within it of a plane is on it.
VERTEX_TOL = 1e-9
# Subsets of rows whose normals are this close to dependent meet in no vertex.
_DET_EPS = 1e-12


@lru_cache(maxsize=256)
def _subsets(m: int, k: int) -> NDArray[np.intp]:
    """All k-subsets of range(m) as an (N, k) index array (cached per (m, k))."""
    out = np.fromiter(
        (i for c in combinations(range(m), k) for i in c), dtype=np.intp, count=-1
    )
    return out.reshape(-1, k)


def _cross(p: NDArray[np.float64], q: NDArray[np.float64]) -> NDArray[np.float64]:
    """Row-wise cross product of (N, 3) arrays (np.cross is several times slower here)."""
    out = np.empty(p.shape)  # callers pass equal shapes
    out[..., 0] = p[..., 1] * q[..., 2] - p[..., 2] * q[..., 1]
    out[..., 1] = p[..., 2] * q[..., 0] - p[..., 0] * q[..., 2]
    out[..., 2] = p[..., 0] * q[..., 1] - p[..., 1] * q[..., 0]
    return out


def is_bounded(a: NDArray[np.float64], eps: float = 1e-12) -> bool:
    """Whether {a t <= b} is bounded (for any b making it non-empty): no recession ray.

    A non-zero recession cone {d : a d <= 0} contains a line (rank a < k) or an extreme
    ray on which k-1 independent rows are tight, i.e. +-(a_i x a_j) in 3D, +-perp(a_i) in
    2D: a finite set of candidates, so no LP is needed.
    """
    m, k = a.shape
    if m <= k:
        return False
    if k == 1:
        return bool(np.any(a[:, 0] > 0) and np.any(a[:, 0] < 0))
    if k == 2:
        d = np.stack([-a[:, 1], a[:, 0]], axis=1)
    else:
        idx = _subsets(m, 2)
        d = _cross(a[idx[:, 0]], a[idx[:, 1]])
        norm = np.sqrt(np.einsum("ij,ij->i", d, d))
        ok = norm > 1e-9
        if not ok.any():
            return False  # all rows parallel: rank 1
        d = d[ok] / norm[ok, None]
    d = np.vstack([d, -d])
    return not bool(np.any(np.all(d @ a.T <= eps, axis=1)))


def _dedupe(v: NDArray[np.float64], tol: float) -> NDArray[np.float64]:
    """Merge points closer than tol (keeping the first of each cluster)."""
    if v.shape[0] <= 1:
        return v
    diff = v[:, None, :] - v[None, :, :]
    close = np.einsum("ijk,ijk->ij", diff, diff) <= tol * tol
    first = np.argmax(close, axis=1)  # index of the first point close to each point
    return v[first == np.arange(v.shape[0])]


def enumerate_vertices(
    a: NDArray[np.float64], b: NDArray[np.float64], tol: float = VERTEX_TOL
) -> NDArray[np.float64]:
    """Vertices (V, k) of the bounded polytope {a t <= b} (k = 1, 2, 3; unit rows)."""
    m, k = a.shape
    if m < k:
        return np.zeros((0, k))
    idx = _subsets(m, k)
    if k == 1:
        ok = np.abs(a[:, 0]) > _DET_EPS
        v = (b[ok] / a[ok, 0])[:, None]
    elif k == 2:
        p, q = a[idx[:, 0]], a[idx[:, 1]]
        bp, bq = b[idx[:, 0]], b[idx[:, 1]]
        det = p[:, 0] * q[:, 1] - p[:, 1] * q[:, 0]
        ok = np.abs(det) > _DET_EPS
        det, p, q, bp, bq = det[ok], p[ok], q[ok], bp[ok], bq[ok]
        v = np.stack([(bp * q[:, 1] - bq * p[:, 1]) / det, (p[:, 0] * bq - q[:, 0] * bp) / det], axis=1)
    elif k == 3:
        p, q, r = a[idx[:, 0]], a[idx[:, 1]], a[idx[:, 2]]
        qr = _cross(q, r)
        det = np.einsum("ij,ij->i", p, qr)
        ok = np.abs(det) > _DET_EPS
        rp = _cross(r[ok], p[ok])
        pq = _cross(p[ok], q[ok])
        v = (
            b[idx[ok, 0], None] * qr[ok] + b[idx[ok, 1], None] * rp + b[idx[ok, 2], None] * pq
        ) / det[ok, None]
    else:
        raise ValueError(f"vertex enumeration supports dimensions 1-3, not {k}")
    feasible = np.all(v @ a.T <= b + tol, axis=1)
    return _dedupe(v[feasible], tol)


def order_polygon(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Convex polygon vertices (V, 2) in counter-clockwise order."""
    c = v.mean(axis=0)
    ang = np.arctan2(v[:, 1] - c[1], v[:, 0] - c[0])
    return v[np.argsort(ang, kind="stable")]


def _tetrahedra(
    a: NDArray[np.float64], b: NDArray[np.float64], v: NDArray[np.float64], tol: float
) -> NDArray[np.float64]:
    """Tetrahedra (T, 4, 3) filling the convex polyhedron with vertices v and rows a, b.

    Each facet (a row with >= 3 vertices on it) is ordered by angle about its centre and
    fanned; every triangle is joined to the vertex centroid. Plain floats per facet: a
    polyhedron has ~6-12 facets of 3-8 vertices, where numpy's per-call cost dominates.
    """
    tight = (np.abs(v @ a.T - b) <= tol).T.tolist()  # (m, V) per row
    pts = v.tolist()
    normals = a.tolist()
    nv = len(pts)
    apex = [sum(p[d] for p in pts) / nv for d in range(3)]
    seen: set[tuple[int, ...]] = set()
    tets: list[list[list[float]]] = []
    for row, on in enumerate(tight):
        idx = tuple(j for j in range(nv) if on[j])
        if len(idx) < 3 or idx in seen:
            continue  # not a facet, or a duplicate plane with the same vertex set
        seen.add(idx)
        nx, ny, nz = normals[row]
        # An in-plane orthonormal basis (u, w): u = n x (x or y axis), w = n x u.
        if abs(nx) < 0.9:
            ux, uy, uz = 0.0, nz, -ny
        else:
            ux, uy, uz = -nz, 0.0, nx
        un = math.sqrt(ux * ux + uy * uy + uz * uz)
        ux, uy, uz = ux / un, uy / un, uz / un
        wx, wy, wz = ny * uz - nz * uy, nz * ux - nx * uz, nx * uy - ny * ux
        k = len(idx)
        cx = sum(pts[j][0] for j in idx) / k
        cy = sum(pts[j][1] for j in idx) / k
        cz = sum(pts[j][2] for j in idx) / k

        def angle(j: int) -> float:
            px, py, pz = pts[j][0] - cx, pts[j][1] - cy, pts[j][2] - cz
            return math.atan2(px * wx + py * wy + pz * wz, px * ux + py * uy + pz * uz)

        ring = sorted(idx, key=angle)
        first = pts[ring[0]]
        for q in range(1, k - 1):
            tets.append([apex, first, pts[ring[q]], pts[ring[q + 1]]])
    return np.array(tets, dtype=float).reshape(-1, 4, 3)


def simplex_measures(simplices: NDArray[np.float64]) -> NDArray[np.float64]:
    """k-dimensional measures of simplices (K, k+1, n) (length, area, volume; 1 for a point)."""
    k = simplices.shape[1] - 1
    if k == 0:
        return np.ones(simplices.shape[0])
    edges = simplices[:, 1:, :] - simplices[:, :1, :]  # (K, k, n)
    n = simplices.shape[2]
    if k == n:  # |det| directly: the Gram determinant would square the rounding error
        return np.abs(np.linalg.det(edges)) / (1.0, 1.0, 2.0, 6.0)[k]
    if k == 1:
        return np.linalg.norm(edges[:, 0, :], axis=1)
    if k == 2 and n == 3:
        return np.linalg.norm(_cross(edges[:, 0, :], edges[:, 1, :]), axis=1) / 2.0
    gram = edges @ np.swapaxes(edges, 1, 2)  # (K, k, k)
    fact = (1.0, 1.0, 2.0, 6.0)[k]
    return np.sqrt(np.maximum(np.linalg.det(gram), 0.0)) / fact


def decompose(
    a: NDArray[np.float64],
    b: NDArray[np.float64],
    ref: NDArray[np.float64] | None,
    bound: float = BOUND,
    tol: float = VERTEX_TOL,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Simplices (K, k+1, k) and vertices (V, k) of {a t <= b}; raises if unbounded.

    `ref` is a point near the set (e.g. its Chebyshev centre), the centre of the bounding
    box used to detect unboundedness; ref None means the caller knows the set is bounded
    (e.g. a piece of a bounded region) and skips that box. Returns no simplices if the set
    is empty or flat.
    """
    k = a.shape[1]
    if k == 0:
        return np.zeros((1, 1, 0)), np.zeros((1, 0))
    if ref is not None and not is_bounded(a):
        raise UnboundedRegionError("the region is unbounded: bound it, e.g. with a workspace")
    v = enumerate_vertices(a, b, tol)
    if ref is not None and v.shape[0] and np.any(np.abs(v - ref) >= bound * (1 - 1e-9)):
        raise UnboundedRegionError(
            f"the region is unbounded (or wider than {bound:g} m): bound it, e.g. with a workspace"
        )
    if v.shape[0] < k + 1:
        return np.zeros((0, k + 1, k)), v
    if k == 1:
        return np.array([[[v[:, 0].min()], [v[:, 0].max()]]]), v
    if k == 2:
        poly = order_polygon(v)
        n = poly.shape[0]
        s = np.empty((n - 2, 3, 2))
        s[:, 0] = poly[0]
        s[:, 1] = poly[1:-1]
        s[:, 2] = poly[2:]
        return s, v
    return _tetrahedra(a, b, v, tol), v
