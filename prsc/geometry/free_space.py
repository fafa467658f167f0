"""Exact decomposition of a convex region minus a union of convex obstacles into disjoint
convex pieces, so a uniform draw from the free space needs no rejection.

For one obstacle O = {a_i p <= b_i, i = 1..m} and a convex piece P:
    P \\ O = union over i of  P  ∩ {a_i p >= b_i} ∩ {a_j p <= b_j, j < i},
pieces with disjoint interiors. Obstacles are subtracted one after another from every
current piece. Rows that cannot cut a piece (all its vertices on one side) are skipped,
a piece that lies outside one obstacle row is kept whole, and zero-measure pieces
(touching contact) are dropped, so the piece count stays small. The work happens in the
region's reduced coordinates (affine.py): a region on a table top is a polygon, and the
obstacles are cut down to their sections by that plane.

An empty result is a proof that no free position exists (up to measure zero, i.e. apart
from exact contact positions): the caller reports a dead end instead of retrying.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Callable, Sequence, TypeVar

import numpy as np
from numpy.typing import NDArray

from prsc.geometry.affine import TOL, AffineRegion, reduce_affine
from prsc.geometry.exceptions import EmptyRegionError
from prsc.geometry.polytope import Polytope
from prsc.geometry.uniform_sampling import SLIVER, UniformSampler
from prsc.geometry.triangulation import BOUND, VERTEX_TOL, decompose, order_polygon, simplex_measures

_FLAT_ROW = 1e-9
# A convex polygon as its vertices in counter-clockwise order (reduced coordinates).
Polygon = list[tuple[float, float]]
_P = TypeVar("_P")  # a piece: a (polygon, area) pair in 2D, a _Piece otherwise


@dataclass(frozen=True, eq=False)
class _Piece:
    a: NDArray[np.float64] | None  # (m, k) unit rows, reduced coordinates (None: polygon)
    b: NDArray[np.float64] | None
    simplices: NDArray[np.float64]  # (K, k+1, k)
    vertices: NDArray[np.float64]  # (V, k)
    measure: float


@dataclass(frozen=True, eq=False)
class FreeSpace:
    """Disjoint convex pieces of region minus obstacles, with a sampler over their union."""

    region: AffineRegion
    pieces: tuple[_Piece, ...]

    @property
    def measure(self) -> float:
        """Total length/area/volume of the free space."""
        return float(sum(p.measure for p in self.pieces))

    @property
    def is_empty(self) -> bool:
        """True if nothing of positive measure is left."""
        return not self.pieces

    def piece_polytopes(self) -> list[Polytope]:
        """Each piece as an ambient H-polytope (with the region's equalities)."""
        reg = self.region
        n, k = reg.basis.shape
        # Equalities: the orthogonal complement of the basis through the origin.
        q, _ = np.linalg.qr(np.hstack([reg.basis, np.eye(n)]))
        comp = q[:, k:n].T
        out = []
        for p in self.pieces:
            at, bt = (p.a, p.b) if p.a is not None else _polygon_rows(p.vertices)
            a = at @ reg.basis.T
            out.append(Polytope.from_rows(a, bt + a @ reg.origin, C=comp, d=comp @ reg.origin, dim=n))
        return out

    def sampler(self) -> UniformSampler:
        """Exact uniform sampler over the free space; raises EmptyRegionError if none is left."""
        if not self.pieces:
            raise EmptyRegionError("no free space left: every position collides with an obstacle")
        s_t = np.concatenate([p.simplices for p in self.pieces])
        reg = self.region
        return UniformSampler(reg.origin + s_t @ reg.basis.T, simplex_measures(s_t))


def _make_piece(a: NDArray, b: NDArray, ref: NDArray | None, bound: float) -> _Piece | None:
    s, v = decompose(a, b, ref, bound)
    if s.shape[0] == 0:
        return None
    w = simplex_measures(s)
    # Rows touching no vertex are redundant: drop them so pieces stay small.
    tight = np.any(np.abs(v @ a.T - b) <= VERTEX_TOL, axis=0)
    return _Piece(a[tight], b[tight], s, v, float(w.sum()))


# Signed distances this small count as "on the line" when clipping polygons.
_ON_LINE = 1e-12


def _clip(poly: Polygon, ax: float, ay: float, b: float) -> Polygon:
    """Sutherland-Hodgman: the convex polygon (CCW list) cut to ax x + ay y <= b."""
    s = [ax * x + ay * y - b for x, y in poly]
    s = [0.0 if -_ON_LINE <= v <= _ON_LINE else v for v in s]
    out: list[tuple[float, float]] = []
    n = len(poly)
    for j in range(n):
        s1, s2 = s[j], s[(j + 1) % n]
        if s1 <= 0.0:
            out.append(poly[j])
        if (s1 < 0.0 < s2) or (s2 < 0.0 < s1):
            (x1, y1), (x2, y2) = poly[j], poly[(j + 1) % n]
            t = s1 / (s1 - s2)
            out.append((x1 + t * (x2 - x1), y1 + t * (y2 - y1)))
    return out


def _polygon_piece(poly: Polygon, area: float) -> _Piece:
    """A 2D piece from a CCW convex polygon: fan triangles; edge rows on demand."""
    v0 = poly[0]
    tris = [(v0, poly[j], poly[j + 1]) for j in range(1, len(poly) - 1)]
    return _Piece(None, None, np.array(tris, dtype=float).reshape(-1, 3, 2), np.array(poly, dtype=float), area)


def _polygon_rows(v: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Outward unit edge rows (a, b) of a CCW convex polygon (V, 2)."""
    edge = np.roll(v, -1, axis=0) - v
    length = np.hypot(edge[:, 0], edge[:, 1])
    ok = length > 0.0
    a = np.stack([edge[ok, 1], -edge[ok, 0]], axis=1) / length[ok, None]
    return a, np.einsum("ij,ij->i", a, v[ok])


def _area(poly: Polygon) -> float:
    """Shoelace area of a CCW polygon (0 for fewer than 3 vertices)."""
    n = len(poly)
    if n < 3:
        return 0.0
    return 0.5 * sum(poly[j][0] * poly[(j + 1) % n][1] - poly[(j + 1) % n][0] * poly[j][1] for j in range(n))


def _subtract_polygons(
    pieces: list[tuple[Polygon, float]], rows: list[tuple[float, float, float]], tol: float
) -> list[tuple[Polygon, float]]:
    """(polygon, area) pieces minus the convex obstacle {ax x + ay y <= b}, by clipping.

    Plain floats: the polygons have a handful of vertices, where numpy's per-call cost
    would dominate. Two Sutherland-Hodgman cuts per obstacle edge.
    """
    out: list[tuple[Polygon, float]] = []
    for poly, area in pieces:
        viol = [[ax * x + ay * y - b for x, y in poly] for ax, ay, b in rows]
        if any(min(v) >= -tol for v in viol):
            out.append((poly, area))  # one obstacle edge separates them
            continue
        remaining = poly
        for (ax, ay, b), v in zip(rows, viol):
            if max(v) <= tol:
                continue  # the piece lies inside this half-plane
            outside = _clip(remaining, -ax, -ay, -b)
            a_out = _area(outside)
            if a_out > SLIVER * area:
                out.append((outside, a_out))
            remaining = _clip(remaining, ax, ay, b)
            if len(remaining) < 3:
                break  # nothing left to cut: later pieces would be empty
    return out


def _subtract(piece: _Piece, oa: NDArray, ob: NDArray, bound: float, tol: float) -> list[_Piece]:
    """piece minus {oa t <= ob} as disjoint pieces of positive measure."""
    viol = piece.vertices @ oa.T - ob  # > 0: vertex outside that obstacle row
    if np.any(np.all(viol >= -tol, axis=0)):
        return [piece]  # one obstacle face separates them (touching at most)
    out: list[_Piece] = []
    acc_a: list[NDArray] = []
    acc_b: list[float] = []
    for i in range(oa.shape[0]):
        if np.max(viol[:, i]) <= tol:
            continue  # the piece lies inside this half-space: {a_i t > b_i} misses it
        a = np.vstack([piece.a, -oa[i : i + 1]] + ([np.array(acc_a)] if acc_a else []))
        b = np.concatenate([piece.b, [-ob[i]], acc_b])
        sub = _make_piece(a, b, None, bound)  # a part of a bounded piece: no bounding box
        if sub is not None and sub.measure > SLIVER * piece.measure:
            out.append(sub)
        acc_a.append(oa[i])
        acc_b.append(float(ob[i]))
    return out


def _reduced_obstacle(reg: AffineRegion, obs: Polytope) -> NDArray[np.float64] | None:
    """Obstacle rows [a_t | b_t] (unit a_t) in the region's coordinates; None if it misses.

    An empty array means the obstacle contains the region's whole affine hull.
    """
    if obs.C.shape[0]:
        raise ValueError("obstacles must be full-dimensional (no equality rows)")
    at, bt = reg.reduce_rows(obs.A, obs.b)
    norms = np.linalg.norm(at, axis=1)
    flat = norms < _FLAT_ROW
    if np.any(bt[flat] < 0.0):
        return None  # a row constant on the hull and violated: the obstacle misses it
    keep = ~flat
    return np.hstack([at[keep] / norms[keep, None], (bt[keep] / norms[keep])[:, None]])


def _subtract_obstacles(
    reg: AffineRegion,
    obstacles: Sequence[Polytope],
    pieces: list[_P],
    cut: Callable[[list[_P], NDArray[np.float64]], list[_P]],
) -> list[_P]:
    """pieces minus every obstacle; `cut(pieces, rows)` subtracts one obstacle's reduced rows."""
    for obs in obstacles:
        rows = _reduced_obstacle(reg, obs)
        if rows is None:
            continue  # the obstacle misses the region
        if rows.shape[0] == 0:
            return []  # the obstacle contains the whole region
        pieces = cut(pieces, rows)
        if not pieces:
            break
    return pieces


def _polygon_cut(tol: float) -> Callable[[list[tuple[Polygon, float]], NDArray[np.float64]], list[tuple[Polygon, float]]]:
    """The 2D cut: polygons clipped in vertex form (CCW order), in plain floats."""

    def cut(polys: list[tuple[Polygon, float]], rows: NDArray[np.float64]) -> list[tuple[Polygon, float]]:
        return _subtract_polygons(polys, [(r[0], r[1], r[2]) for r in rows.tolist()], tol)

    return cut


def _piece_cut(tol: float, bound: float) -> Callable[[list[_Piece], NDArray[np.float64]], list[_Piece]]:
    """The 1D and 3D cut: each piece split into convex parts outside the obstacle."""

    def cut(pieces: list[_Piece], rows: NDArray[np.float64]) -> list[_Piece]:
        at, bt = rows[:, :-1], rows[:, -1]
        return [sub for piece in pieces for sub in _subtract(piece, at, bt, bound, tol)]

    return cut


@dataclass(frozen=True, eq=False)
class RegionBase:
    """A region reduced to its affine hull and split into working pieces (polygons in 2D),
    minus the obstacles given to `region_base`: where `free_space` starts."""

    reg: AffineRegion
    pieces: tuple[Any, ...] | None  # None: the region has measure zero

    def translated(self, shift: NDArray[np.float64]) -> RegionBase:
        """The start of the region plus `shift` (its pieces are in reduced coordinates: unchanged)."""
        return RegionBase(replace(self.reg, origin=self.reg.origin + shift), self.pieces)


def region_base(region: Polytope, fixed: Sequence[Polytope] = (), tol: float = TOL, bound: float = BOUND) -> RegionBase:
    """The region's reduction and pieces minus the `fixed` obstacles, to decompose it again
    with other obstacles (the fixed ones subtracted once: a robot's hole about its base)."""
    reg = reduce_affine(region, tol)
    first = _make_piece(reg.A, reg.b, reg.center, bound) if reg.dim else None
    if first is None or reg.dim == 0:
        return RegionBase(reg, None if reg.dim else ())
    if reg.dim == 2:
        start: Polygon = [(x, y) for x, y in order_polygon(first.vertices).tolist()]
        pieces: list[Any] = _subtract_obstacles(reg, fixed, [(start, _area(start))], _polygon_cut(tol))
    else:
        pieces = _subtract_obstacles(reg, fixed, [first], _piece_cut(tol, bound))
    return RegionBase(reg, tuple(pieces))


def free_space(
    region: Polytope,
    obstacles: Sequence[Polytope],
    tol: float = TOL,
    bound: float = BOUND,
    base: RegionBase | None = None,
) -> FreeSpace:
    """Decompose region minus the union of (full-dimensional) obstacles into convex pieces
    (`base`: `region_base(region, fixed, tol, bound)` computed before: its fixed obstacles are
    subtracted too).

    Raises EmptyRegionError if the region itself is empty, UnboundedRegionError if it is
    unbounded; an empty FreeSpace (no pieces) if obstacles cover it.
    """
    if base is None:
        base = region_base(region, (), tol, bound)
    reg = base.reg
    if reg.dim == 0:
        point = reg.origin
        for obs in obstacles:
            if obs.C.shape[0]:
                raise ValueError("obstacles must be full-dimensional (no equality rows)")
            an = np.linalg.norm(obs.A, axis=1)
            if np.all(obs.A @ point - obs.b < -tol * an):
                return FreeSpace(reg, ())
        return FreeSpace(reg, (_Piece(np.zeros((0, 0)), np.zeros(0), np.zeros((1, 1, 0)), np.zeros((1, 0)), 1.0),))
    if base.pieces is None:
        raise EmptyRegionError("the region has measure zero")
    if reg.dim == 2:
        polys = _subtract_obstacles(reg, obstacles, list(base.pieces), _polygon_cut(tol)) if base.pieces else []
        return FreeSpace(reg, tuple(_polygon_piece(p, area) for p, area in polys))
    pieces = _subtract_obstacles(reg, obstacles, list(base.pieces), _piece_cut(tol, bound)) if base.pieces else []
    return FreeSpace(reg, tuple(pieces))


def free_space_sampler(
    region: Polytope, obstacles: Sequence[Polytope], tol: float = TOL, bound: float = BOUND,
    base: RegionBase | None = None,
) -> UniformSampler:
    """Exact uniform sampler over region minus obstacles; EmptyRegionError proves a dead end."""
    return free_space(region, obstacles, tol, bound, base).sampler()
