"""Convex polytopes in H-representation: {p : A p <= b, C p = d}, with labelled rows.

Each row carries an opaque integer label (NO_LABEL = -1 for none): the caller maps it to
the specifier or source span that produced the row, so an empty intersection can be
explained (see `iis.py`). Intersection is stacking rows; erosion by an oriented box is
closed-form through the box's support function (the paper's eq. 5-6 without an LP).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prsc.geometry.boxes import Box

NO_LABEL = -1


def _labels(labels: ArrayLike | int | None, n: int) -> NDArray[np.int64]:
    if labels is None:
        return np.full(n, NO_LABEL, dtype=np.int64)
    if np.ndim(labels) == 0:
        return np.full(n, int(labels), dtype=np.int64)  # type: ignore[arg-type]
    out = np.asarray(labels, dtype=np.int64).reshape(-1)
    if out.shape[0] != n:
        raise ValueError(f"{out.shape[0]} labels for {n} rows")
    return out


@dataclass(frozen=True, eq=False)
class Polytope:
    """{p : A p <= b, C p = d} in R^dim; `labels`/`eq_labels` tag each row (int, -1 = none)."""

    A: NDArray[np.float64]
    b: NDArray[np.float64]
    C: NDArray[np.float64]
    d: NDArray[np.float64]
    labels: NDArray[np.int64]
    eq_labels: NDArray[np.int64]

    @classmethod
    def from_rows(
        cls,
        A: ArrayLike,
        b: ArrayLike,
        labels: ArrayLike | int | None = None,
        C: ArrayLike | None = None,
        d: ArrayLike | None = None,
        eq_labels: ArrayLike | int | None = None,
        dim: int | None = None,
    ) -> Polytope:
        """Build from inequality rows A p <= b and optional equality rows C p = d."""
        a = np.asarray(A, dtype=float)
        if dim is None:
            dim = a.shape[1] if a.ndim == 2 and a.size else np.asarray(C, dtype=float).shape[-1]
        a = a.reshape(-1, dim)
        bb = np.asarray(b, dtype=float).reshape(-1)
        cc = np.zeros((0, dim)) if C is None else np.asarray(C, dtype=float).reshape(-1, dim)
        dd = np.zeros(0) if d is None else np.asarray(d, dtype=float).reshape(-1)
        if a.shape[0] != bb.shape[0] or cc.shape[0] != dd.shape[0]:
            raise ValueError("row count mismatch between A/b or C/d")
        if not all(np.all(np.isfinite(x)) for x in (a, bb, cc, dd)):
            raise ValueError("non-finite polytope coefficients")
        return cls(a, bb, cc, dd, _labels(labels, a.shape[0]), _labels(eq_labels, cc.shape[0]))

    @classmethod
    def everything(cls, dim: int = 3) -> Polytope:
        """The whole space R^dim (no rows)."""
        return cls.from_rows(np.zeros((0, dim)), np.zeros(0), dim=dim)

    @classmethod
    def halfspace(cls, normal: ArrayLike, offset: float, label: int = NO_LABEL) -> Polytope:
        """{p : normal . p <= offset}."""
        n = np.asarray(normal, dtype=float).reshape(1, -1)
        return cls.from_rows(n, [offset], label)

    @classmethod
    def plane(cls, normal: ArrayLike, offset: float, label: int = NO_LABEL) -> Polytope:
        """{p : normal . p = offset}."""
        n = np.asarray(normal, dtype=float).reshape(1, -1)
        return cls.from_rows(np.zeros((0, n.shape[1])), [], C=n, d=[offset], eq_labels=label)

    @classmethod
    def from_box(cls, box: Box, label: int = NO_LABEL) -> Polytope:
        """The solid box as 6 rows (+-R e_i) . p <= (+-R e_i) . c + h_i."""
        axes = box.rotation.T  # rows = local axes in world
        a = np.vstack([axes, -axes])
        mid = axes @ box.center
        b = np.concatenate([mid + box.half_extents, -mid + box.half_extents])
        return cls.from_rows(a, b, label)

    @classmethod
    def from_rectangle(
        cls, center: ArrayLike, rotation: ArrayLike, width: float, length: float, label: int = NO_LABEL
    ) -> Polytope:
        """A planar rectangle: the box (width, length, 0) as 4 rows plus one equality row."""
        r = np.asarray(rotation, dtype=float)
        c = np.asarray(center, dtype=float)
        u, v, w = r[:, 0], r[:, 1], r[:, 2]
        a = np.vstack([u, -u, v, -v])
        b = np.array([u @ c + width / 2, -(u @ c) + width / 2, v @ c + length / 2, -(v @ c) + length / 2])
        return cls.from_rows(a, b, label, C=w[None, :], d=[w @ c], eq_labels=label)

    @property
    def dim(self) -> int:
        """Ambient dimension."""
        return int(self.A.shape[1])

    @property
    def num_rows(self) -> int:
        """Number of inequality plus equality rows."""
        return int(self.A.shape[0] + self.C.shape[0])

    def intersect(self, *others: Polytope) -> Polytope:
        """Intersection with other polytopes: all rows stacked (labels kept)."""
        return intersect(self, *others)

    def with_label(self, label: int) -> Polytope:
        """Same set, every row relabelled `label`."""
        return Polytope(self.A, self.b, self.C, self.d, _labels(label, len(self.b)), _labels(label, len(self.d)))

    def contains(self, points: ArrayLike, tol: float = 1e-9) -> NDArray[np.bool_]:
        """Whether each point (..., dim) satisfies every row within tol (rows taken as unit)."""
        p = np.asarray(points, dtype=float)
        an = np.linalg.norm(self.A, axis=1)
        cn = np.linalg.norm(self.C, axis=1)
        ok = np.all(p @ self.A.T - self.b <= tol * np.maximum(an, 1.0), axis=-1)
        if len(self.d):
            ok &= np.all(np.abs(p @ self.C.T - self.d) <= tol * np.maximum(cn, 1.0), axis=-1)
        return ok

    def same_rows(self, other: Polytope) -> bool:
        """Whether `other` has exactly these rows (labels aside)."""
        return (self.A.shape == other.A.shape and self.C.shape == other.C.shape and np.array_equal(self.A, other.A)
                and np.array_equal(self.b, other.b) and np.array_equal(self.C, other.C) and np.array_equal(self.d, other.d))

    def translate(self, offset: ArrayLike) -> Polytope:
        """The set shifted by `offset`."""
        v = np.asarray(offset, dtype=float)
        return Polytope(self.A, self.b + self.A @ v, self.C, self.d + self.C @ v, self.labels, self.eq_labels)

    def normalized(self) -> Polytope:
        """Same set with unit-length rows (constant rows 0 . p <= b kept as they are)."""
        an = np.linalg.norm(self.A, axis=1)
        cn = np.linalg.norm(self.C, axis=1)
        an = np.where(an > 0, an, 1.0)
        cn = np.where(cn > 0, cn, 1.0)
        return Polytope(self.A / an[:, None], self.b / an, self.C / cn[:, None], self.d / cn, self.labels, self.eq_labels)

    def erode_by_box(self, rotation: ArrayLike, half_extents: ArrayLike, tol: float = 1e-12) -> Polytope:
        """Positions p at which the box (rotation, half extents) centred at p lies inside."""
        return erode_by_box(self, rotation, half_extents, tol)


def intersect(*polys: Polytope) -> Polytope:
    """Intersection of polytopes of the same dimension: all rows stacked, labels kept."""
    if not polys:
        raise ValueError("intersect() needs at least one polytope")
    dims = {p.dim for p in polys}
    if len(dims) != 1:
        raise ValueError(f"cannot intersect polytopes of dimensions {sorted(dims)}")
    return Polytope(
        np.vstack([p.A for p in polys]),
        np.concatenate([p.b for p in polys]),
        np.vstack([p.C for p in polys]),
        np.concatenate([p.d for p in polys]),
        np.concatenate([p.labels for p in polys]),
        np.concatenate([p.eq_labels for p in polys]),
    )


def erode_by_box(poly: Polytope, rotation: ArrayLike, half_extents: ArrayLike, tol: float = 1e-12) -> Polytope:
    """Morphological erosion of `poly` by an origin-centred box: rows b_i - s(a_i).

    s is positively homogeneous, so s(a_i) = |a_i| s(a_i/|a_i|) and no LP is needed. An
    equality row c p = d survives only if the box is flat along c (s(c) <= tol); otherwise
    no box of positive thickness fits in a plane and the row becomes the empty pair
    c p <= d - s, -c p <= -d - s (labels kept, so the conflict can be explained).
    """
    r = np.asarray(rotation, dtype=float)
    h = np.asarray(half_extents, dtype=float)
    b = poly.b - np.abs(poly.A @ r) @ h
    sc = np.abs(poly.C @ r) @ h
    flat = sc <= tol * np.maximum(np.linalg.norm(poly.C, axis=1), 1.0)
    if np.all(flat):
        return Polytope(poly.A, b, poly.C, poly.d, poly.labels, poly.eq_labels)
    thick = ~flat
    a_new = np.vstack([poly.A, poly.C[thick], -poly.C[thick]])
    b_new = np.concatenate([b, poly.d[thick] - sc[thick], -poly.d[thick] - sc[thick]])
    lab = np.concatenate([poly.labels, poly.eq_labels[thick], poly.eq_labels[thick]])
    return Polytope(a_new, b_new, poly.C[flat], poly.d[flat], lab, poly.eq_labels[flat])
