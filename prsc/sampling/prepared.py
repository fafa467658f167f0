"""A feasible region ready for drawing (prepared once, drawn from many times): its exact
sampler, bounds and affine hull, and the start of its free-space decompositions."""

from __future__ import annotations

from collections import OrderedDict

import numpy as np

from prsc.geometry.affine import AffineRegion, reduce_affine
from prsc.geometry.exceptions import EmptyRegionError
from prsc.geometry.free_space import RegionBase, free_space_sampler, region_base
from prsc.geometry.hit_and_run import hit_and_run
from prsc.geometry.polytope import Polytope
from prsc.geometry.uniform_sampling import UniformSampler, prepare_sampler

TOL = 1e-9  # metres: feasibility tolerance of a point against its rows
_BASES = 8  # free-space starts kept per prepared region (by translation)


class Prepared:
    """A non-empty region ready for drawing: exact sampler, bounds, affine hull (lazily)."""

    __slots__ = ("poly", "sampler", "point", "lo", "hi", "_affine", "_bases", "__weakref__")  # weak: proposal.py's cells

    def __init__(self, poly: Polytope, sampler: UniformSampler | None, point: np.ndarray | None = None) -> None:
        self.poly = poly
        self.sampler = sampler
        self.point = point
        if point is not None:
            self.lo = self.hi = point
        else:
            assert sampler is not None
            self.lo, self.hi = sampler.bounds()
        self._affine: AffineRegion | None = None
        # The free-space decomposition's start (a pure function of the rows, so which scene filled
        # it never matters): one for every translation, and per translation with fixed cells.
        self._bases: OrderedDict[bytes, RegionBase] = OrderedDict()

    @property
    def dim(self) -> int:
        """Intrinsic dimension (0 point ... 3 solid)."""
        return 0 if self.point is not None else self.sampler.dim  # type: ignore[union-attr]

    @property
    def measure(self) -> float:
        """Length, area or volume (1 for a point)."""
        return 1.0 if self.point is not None else self.sampler.measure  # type: ignore[union-attr]

    def draw(self, rng: np.random.Generator, method: str, walk_length: int) -> np.ndarray:
        """One point: exact uniform, or the end of a hit-and-run walk from the Chebyshev centre."""
        if self.point is not None:
            return self.point.copy()
        if method == "hit-and-run":
            if self._affine is None:
                self._affine = reduce_affine(self.poly)
            return hit_and_run(self._affine, rng, 1, walk_length)[0]
        return self.sampler.sample_one(rng)  # type: ignore[union-attr]


    def free_space(self, shift: np.ndarray | None, obstacles: list[Polytope], fixed: list[Polytope] = ()) -> UniformSampler:  # type: ignore[assignment]
        """Exact sampler of the region (plus `shift`) minus `fixed` cells and `obstacles`; EmptyRegionError
        if nothing is free. The region minus `fixed` (a robot's hole, the same in every scene) is kept."""
        poly = self.poly if shift is None else self.poly.translate(shift)
        if not fixed:
            # The start of region + t is the region's own, its affine hull moved by t: the
            # reduced rows, centre and pieces are the same (P + t = {origin + t + basis y : A y <= b}).
            base = self._bases.get(b"")
            if base is None:
                base = self._bases[b""] = region_base(self.poly)
            if shift is not None:
                base = base.translated(shift)
            return free_space_sampler(poly, obstacles, base=base)
        key = (b"" if shift is None else shift.tobytes()) + b"".join(c.A.tobytes() + c.b.tobytes() for c in fixed)
        base = self._bases.get(key)
        if base is None:
            base = self._bases[key] = region_base(poly, fixed)
            if len(self._bases) > _BASES:
                self._bases.popitem(last=False)
        return free_space_sampler(poly, obstacles, base=base)


def prepare(poly: Polytope) -> Prepared:
    """Prepare a region; raises EmptyRegionError / UnboundedRegionError."""
    point = _pinned(poly)
    if point is not None:
        return Prepared(poly, None, point)
    return Prepared(poly, prepare_sampler(poly))


def _pinned(poly: Polytope) -> np.ndarray | None:
    """The point three independent equality rows fix, if they do; EmptyRegionError if it violates a row."""
    c = poly.C
    if c.shape[0] < 3:
        return None
    if c.shape[0] == 3 and c[0, 0] == 1.0 and c[1, 1] == 1.0 and c[2, 2] == 1.0 and not np.any(c - np.diag(np.diag(c))):
        point = poly.d.copy()  # `at V`: the identity rows, solved exactly
    else:
        _, s, _ = np.linalg.svd(c)
        if s[2] <= 1e-9 * max(1.0, s[0]):
            return None
        point, *_ = np.linalg.lstsq(c, poly.d, rcond=None)
    if not satisfies(poly, point):
        raise EmptyRegionError("the point fixed by the equalities violates a row")
    return point


def row_norms(poly: Polytope) -> tuple[np.ndarray, np.ndarray]:
    """max(|row|, 1) of the inequality and equality rows (the tolerance scale)."""
    return (
        np.maximum(np.sqrt(np.einsum("ij,ij->i", poly.A, poly.A)), 1.0),
        np.maximum(np.sqrt(np.einsum("ij,ij->i", poly.C, poly.C)), 1.0),
    )


def satisfies(
    poly: Polytope, p: np.ndarray, norms: tuple[np.ndarray, np.ndarray] | None = None, tol: float = TOL, skip_eq: bool = False
) -> bool:
    """Whether p meets every row of poly to within tol metres."""
    if not len(poly.b) and (skip_eq or not len(poly.d)):
        return True
    an, cn = row_norms(poly) if norms is None else norms
    if len(poly.b) and np.any(poly.A @ p - poly.b > tol * an):
        return False
    if len(poly.d) and not skip_eq and np.any(np.abs(poly.C @ p - poly.d) > tol * cn):
        return False
    return True
