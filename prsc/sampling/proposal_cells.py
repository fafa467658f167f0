"""The cells a falsification proposal draws from (docs/falsify.md): each region cut into a grid
of cells (and fine cells), each cell an exact uniform sampler, cut once while its region lives."""

from __future__ import annotations

import weakref
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from prsc.geometry.exceptions import GeometryError
from prsc.geometry.free_space import free_space_sampler
from prsc.geometry.polytope import Polytope, intersect
from prsc.geometry.uniform_sampling import UniformSampler, prepare_sampler

GRID = {1: 8, 2: 8, 3: 4}  # cells per active axis of a position's region
REFINE = {1: 4, 2: 4, 3: 2}  # fine cells per cell and axis: 32 per axis in 1-D and 2-D, 8 in 3-D
EXTENT = 1e-9  # metres: an axis of the region's box narrower than this is not gridded


@dataclass
class Cells:
    """A region cut into grid cells: exact samplers and spec masses (zero for an empty cell).

    Each cell also splits into REFINE fine cells per axis, cut (exactly, by the same sampler)
    only when a proposal names one: replays near a failure draw from them."""

    lo: np.ndarray
    hi: np.ndarray
    axes: np.ndarray  # the gridded axes
    k: int  # cells per gridded axis
    samplers: list[UniformSampler | None]
    mass: np.ndarray  # each cell's share of the region's measure
    piece_of: Callable[[Polytope], UniformSampler] | None = None  # the region cut by a box
    measure: float = 1.0  # the region's measure (the sum of its cells')
    dim: int = 0
    fine: dict[int, UniformSampler | None] = field(default_factory=dict)  # fine cell -> its sampler, once cut
    fine_masses: dict[int, float] = field(default_factory=dict)  # fine cell -> its share, once cut

    def coords(self, p: np.ndarray) -> np.ndarray:
        """p in [0, 1] per gridded axis of the region's box."""
        span = self.hi[self.axes] - self.lo[self.axes]
        return np.clip((p[self.axes] - self.lo[self.axes]) / span, 0.0, 1.0)

    def fine_sampler(self, flat: int) -> UniformSampler | None:
        """The exact sampler of fine cell `flat` (None: no mass), cut on first use."""
        if flat not in self.fine:
            self.fine[flat] = _cut_box(self.piece_of, self.lo, self.hi, self.axes, fine_k(self.k, len(self.axes)),
                                       flat, self.dim)  # type: ignore[arg-type]
        return self.fine[flat]

    def fine_mass(self, flat: int) -> float:
        """Fine cell `flat`'s share of the region's measure."""
        mass = self.fine_masses.get(flat)
        if mass is None:
            piece = self.fine_sampler(flat)
            mass = self.fine_masses[flat] = 0.0 if piece is None else min(1.0, piece.measure / self.measure)
        return mass


def fine_k(k: int, dims: int) -> int:
    """Fine cells per axis of a grid of k cells per axis over `dims` axes."""
    return k * REFINE[dims]


def grid_index(u: np.ndarray, k: int) -> int:
    """The flat index of the grid cell holding normalised coordinates u, k cells per axis."""
    index = 0
    for x in u:
        index = index * k + min(int(x * k), k - 1)
    return index


def _cut_box(piece_of: Callable[[Polytope], UniformSampler], lo: np.ndarray, hi: np.ndarray, axes: np.ndarray,
             k: int, flat: int, dim: int) -> UniformSampler | None:
    """The region cut by grid box `flat` (k per axis over `axes`), or None when that has no mass of its own."""
    digits = np.unravel_index(flat, (k,) * len(axes))
    a_rows, b_rows = [], []
    for axis, digit in zip(axes, digits):
        step = (hi[axis] - lo[axis]) / k
        row = np.zeros(3)
        row[axis] = 1.0
        a_rows += [row, -row]
        b_rows += [lo[axis] + (digit + 1) * step, -(lo[axis] + digit * step)]
    try:
        piece = piece_of(Polytope.from_rows(a_rows, b_rows))
    except GeometryError:
        return None
    if piece is not None and (piece.dim < dim or piece.measure <= 0.0):
        return None  # a face shared with a neighbour: no mass of its own
    return piece


def cut_into_cells(piece_of: Callable[[Polytope], UniformSampler], lo: np.ndarray, hi: np.ndarray,
                   measure: float, dim: int) -> Cells | None:
    """The grid cells of a region (piece_of(box): the region cut by the box), or None when it is a point."""
    axes = np.nonzero(hi - lo > EXTENT)[0]
    if dim == 0 or not len(axes):
        return None
    k = GRID[len(axes)]
    samplers = [_cut_box(piece_of, lo, hi, axes, k, flat, dim) for flat in range(k ** len(axes))]
    mass = [0.0 if piece is None else piece.measure for piece in samplers]
    total = max(sum(mass), measure * 1e-12)
    shares = np.array(mass) / total
    return Cells(lo, hi, axes, k, samplers, shares / shares.sum(), piece_of, total, dim)


# Prepared region or free space -> its cells, while it lives (static and anchored ones live
# with the sampler, a scene's own ones with the scene).
_CELLS: weakref.WeakKeyDictionary[Any, Cells | None] = weakref.WeakKeyDictionary()


def _cached(owner: Any, cut: Callable[[], Cells | None]) -> Cells | None:
    """The cells of `owner` (a prepared region or free space), cut once while it lives."""
    try:
        return _CELLS[owner]
    except KeyError:
        cells = _CELLS[owner] = cut()
        return cells


def region_cells(region: Any) -> Cells | None:
    """The cells of a prepared region (cut once per prepared region: static and anchored ones are reused)."""
    return _cached(region, lambda: None if region.point is not None else cut_into_cells(
        lambda box: prepare_sampler(intersect(region.poly, box)), region.lo, region.hi, region.measure, region.dim))


def free_space_cells(free: UniformSampler, region: Any, obstacles: list[Polytope]) -> Cells | None:
    """The cells of a static region minus static obstacles (each cell decomposed exactly)."""
    lo, hi = free.bounds()
    return _cached(free, lambda: cut_into_cells(
        lambda box: free_space_sampler(intersect(region.poly, box), obstacles), lo, hi, free.measure, free.dim))


