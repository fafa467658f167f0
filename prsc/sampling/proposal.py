"""A proposal law over a spec's random inputs that only reweights its feasible set.

Each *site* (one object's position, one `(lo, hi)` range draw) gets a defensive mixture

    q = eps * (the spec's law on the site) + (1 - eps) * sum_c w_c * uniform(cell c)

where the cells partition the site's domain: for a position, a grid over the bounding box
of the object's feasible region *in the scene at hand* (cell c is the region cut by the
grid box, prepared by the same exact sampler, so every draw is inside the region); for a
range, equal bins of its unit interval. Cells live in the region's normalised coordinates,
so "the corner of the tray" is the same cell wherever the tray went. The density ratio of
a draw is p/q = 1 / (eps + (1 - eps) w_c / f_c), f_c the spec's mass of cell c (its share
of the region's measure), so the scene's importance weight under the *sequential* law
(docs/sampling.md) is the product over its sites (docs/falsify.md says what it targets).
A site without weights (every site of the initial proposal) draws exactly as the spec's law
does, draw for draw, with ratio 1: round 0 of a campaign is the scenes `prsc sample` draws.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from prsc.errors import PrscError
from prsc.geometry.exceptions import GeometryError
from prsc.geometry.polytope import Polytope, intersect
from prsc.geometry.sampler import UniformSampler, prepare_sampler

FORMAT = "prsc-proposal/1"
DEFAULT_EPS = 0.2  # defensive share of the spec's own law: every ratio <= 1 / eps per site
RANGE_BINS = 8
GRID = {1: 8, 2: 4, 3: 3}  # cells per active axis of a position's region
EXTENT = 1e-9  # metres: an axis of the region's box narrower than this is not gridded


@dataclass
class Cells:
    """A region cut into grid cells: exact samplers and spec masses (zero for an empty cell)."""

    lo: np.ndarray
    hi: np.ndarray
    axes: np.ndarray  # the gridded axes
    k: int  # cells per gridded axis
    samplers: list[UniformSampler | None]
    mass: np.ndarray  # each cell's share of the region's measure

    def cell_of(self, p: np.ndarray) -> int:
        """The index of the cell holding p (region coordinates)."""
        return _flat(self.coords(p), self.k)

    def coords(self, p: np.ndarray) -> np.ndarray:
        """p in [0, 1] per gridded axis of the region's box."""
        span = self.hi[self.axes] - self.lo[self.axes]
        return np.clip((p[self.axes] - self.lo[self.axes]) / span, 0.0, 1.0)


def _flat(u: np.ndarray, k: int) -> int:
    index = 0
    for x in u:
        index = index * k + min(int(x * k), k - 1)
    return index


def cut_into_cells(poly: Polytope, lo: np.ndarray, hi: np.ndarray, measure: float, dim: int) -> Cells | None:
    """The region's grid cells, or None when it is a point (nothing to reweight)."""
    axes = np.nonzero(hi - lo > EXTENT)[0]
    if dim == 0 or not len(axes):
        return None
    k = GRID[len(axes)]
    samplers: list[UniformSampler | None] = []
    mass = []
    for flat in range(k ** len(axes)):
        digits = np.unravel_index(flat, (k,) * len(axes))
        a_rows, b_rows = [], []
        for axis, digit in zip(axes, digits):
            step = (hi[axis] - lo[axis]) / k
            row = np.zeros(3)
            row[axis] = 1.0
            a_rows += [row, -row]
            b_rows += [lo[axis] + (digit + 1) * step, -(lo[axis] + digit * step)]
        try:
            piece = prepare_sampler(intersect(poly, Polytope.from_rows(a_rows, b_rows)))
        except GeometryError:
            piece = None
        if piece is not None and (piece.dim < dim or piece.measure <= 0.0):
            piece = None  # a face shared with a neighbour: no mass of its own
        samplers.append(piece)
        mass.append(0.0 if piece is None else piece.measure)
    shares = np.array(mass) / max(sum(mass), measure * 1e-12)
    return Cells(lo, hi, axes, k, samplers, shares / shares.sum())


@dataclass
class Proposal:
    """Per site, the cell weights w (a site absent keeps the spec's law); eps the defensive share."""

    weights: dict[str, list[float]] = field(default_factory=dict)
    eps: float = DEFAULT_EPS
    law: str = "sequential"

    def to_json(self) -> dict[str, Any]:
        """The proposal as DIR/proposal.json stores it."""
        return {"format": FORMAT, "law": self.law, "eps": self.eps, "range_bins": RANGE_BINS,
                "grid": {str(k): v for k, v in GRID.items()}, "weights": self.weights}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> Proposal:
        """Read what to_json wrote."""
        if not isinstance(data, dict) or data.get("format") != FORMAT:
            raise PrscError(f"not a prsc proposal (expected \"format\": \"{FORMAT}\")")
        eps = float(data.get("eps", DEFAULT_EPS))
        if not 0.0 < eps <= 1.0:
            raise PrscError(f"a proposal's eps must be in (0, 1], got {eps}")
        weights = {str(k): [float(x) for x in v] for k, v in data.get("weights", {}).items()}
        for site, w in weights.items():
            if any(x < 0 or not np.isfinite(x) for x in w) or not sum(w) > 0:
                raise PrscError(f"proposal site {site}: weights must be >= 0, finite and not all 0")
        return cls(weights, eps, str(data.get("law", "sequential")))

    def scene_state(self) -> ProposalState:
        """The per-scene state a SceneContext carries while a scene is drawn."""
        return ProposalState(self)


def load_proposal(path: str | Path) -> Proposal:
    """DIR/proposal.json, with a clear error when it is not one."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as error:
        raise PrscError(f"cannot read the proposal {path}: {error.strerror or error}") from None
    except ValueError as error:
        raise PrscError(f"{path}: invalid JSON: {error}") from None
    try:
        return Proposal.from_json(data)
    except PrscError as error:
        raise PrscError(f"{path}: {error.message}") from None


_CELLS: dict[int, tuple[Any, Cells | None]] = {}  # id(prepared region) -> (region, its cells)


def region_cells(region: Any) -> Cells | None:
    """The cells of a prepared region (cut once per prepared region: static and anchored ones are reused)."""
    hit = _CELLS.get(id(region))
    if hit is not None and hit[0] is region:
        return hit[1]
    if len(_CELLS) > 4096:
        _CELLS.clear()
    cells = None if region.point is not None else cut_into_cells(region.poly, region.lo, region.hi, region.measure, region.dim)
    _CELLS[id(region)] = (region, cells)
    return cells


@dataclass
class Draw:
    """One site's draw in a scene: its density ratio p/q and where it fell (normalised coordinates)."""

    ratio: float
    coords: list[float]


class ProposalState:
    """The draws of one scene under a proposal: site -> Draw, forgotten on a backtrack."""

    def __init__(self, proposal: Proposal) -> None:
        self.proposal = proposal
        self.draws: dict[tuple[str, int], Draw] = {}
        self.masses: dict[str, np.ndarray] = {}  # per site, the spec's mass of each cell (for fitting)

    def rollback(self, level: int) -> None:
        """Forget the draws made while placing objects >= level (SceneContext.rollback)."""
        for key in [key for key in self.draws if key[1] >= level]:
            del self.draws[key]

    def weight(self) -> float:
        """The scene's importance weight: the product of its sites' ratios."""
        return float(np.prod([d.ratio for d in self.draws.values()])) if self.draws else 1.0

    def features(self) -> dict[str, list[float]]:
        """Where each site's draw fell (normalised coordinates), by site."""
        out: dict[str, list[float]] = {}
        for (site, level), draw in sorted(self.draws.items()):
            out[f"{site}@{level}" if site in out else site] = draw.coords
        return out

    def _pick(self, site: str, mass: np.ndarray, u: float, v: float) -> tuple[int | None, np.ndarray]:
        """The cell to draw from (None: the spec's law) and the site's weights."""
        w = self.proposal.weights.get(site)
        weights = mass if w is None or len(w) != len(mass) else np.asarray(w, dtype=float) * (mass > 0)
        total = weights.sum()
        if not total > 0:
            weights, total = mass, mass.sum()
        weights = weights / total
        if u < self.proposal.eps:
            return None, weights
        return min(int(np.searchsorted(np.cumsum(weights), v, side="right")), len(weights) - 1), weights

    def position(self, name: str, level: int, region: Any, ctx: Any) -> np.ndarray:
        """A position drawn from the proposal on the prepared region (region coordinates)."""
        cells = region_cells(region)
        if cells is None:
            return region.draw(ctx.rng, "exact", 1)
        site = f"position:{name}"
        self.masses[site] = cells.mass
        if site not in self.proposal.weights:  # the spec's law, draw for draw as without a proposal
            p = region.draw(ctx.rng, "exact", 1)
            self.draws[(site, level)] = Draw(1.0, [round(float(x), 6) for x in cells.coords(p)])
            return p
        cell, weights = self._pick(site, cells.mass, ctx.uniform(), ctx.uniform())
        if cell is not None and cells.samplers[cell] is None:
            cell = None  # rounding put the pick on an empty cell: fall back to the spec's law
        p = region.draw(ctx.rng, "exact", 1) if cell is None else cells.samplers[cell].sample_one(ctx.rng)
        at = cells.cell_of(p)
        f = cells.mass[at]
        ratio = 1.0 if f <= 0 else 1.0 / (self.proposal.eps + (1 - self.proposal.eps) * weights[at] / f)
        self.draws[(site, level)] = Draw(ratio, [round(float(x), 6) for x in cells.coords(p)])
        return p

    def spec_position(self, name: str, level: int) -> None:
        """The object's position came from the spec's own law (ratio 1): forget an earlier proposal draw."""
        self.draws.pop((f"position:{name}", level), None)

    def unit(self, site: str, ctx: Any) -> float:
        """A draw on [0, 1) for a range at `site` (spec law: uniform)."""
        mass = np.full(RANGE_BINS, 1.0 / RANGE_BINS)
        site = f"range:{site}"
        self.masses[site] = mass
        if site not in self.proposal.weights:  # the spec's law, draw for draw as without a proposal
            u = ctx.uniform()
            self.draws[(site, ctx.level)] = Draw(1.0, [round(u, 6)])
            return u
        cell, weights = self._pick(site, mass, ctx.uniform(), ctx.uniform())
        x = ctx.uniform()
        u = x if cell is None else (cell + x) / RANGE_BINS
        at = min(int(u * RANGE_BINS), RANGE_BINS - 1)
        ratio = 1.0 / (self.proposal.eps + (1 - self.proposal.eps) * weights[at] / mass[at])
        self.draws[(site, ctx.level)] = Draw(ratio, [round(u, 6)])
        return u


def cell_index(coords: list[float], cells: int) -> int:
    """The cell of normalised coordinates on a grid of `cells` cells (cells per axis ** axes)."""
    k = int(round(cells ** (1.0 / max(len(coords), 1))))
    return _flat(np.asarray(coords, dtype=float), k)


def cross_entropy_step(proposal: Proposal, masses: dict[str, np.ndarray], episodes: list[tuple[dict, float, bool]],
                       smoothing: float = 0.7) -> Proposal:
    """One cross-entropy update toward the failures (elite set = the failed episodes).

    Per site the maximiser of sum over failures of W log q is the failures' importance-weighted
    share per cell; it is mixed with the current weights (`smoothing`, as VerifAI does) so no
    cell of positive mass ever gets weight zero. `episodes`: (features, weight, failed)."""
    weights = dict(proposal.weights)
    for site, mass in masses.items():
        old = np.asarray(weights.get(site, mass), dtype=float)
        if len(old) != len(mass):
            old = mass
        target = np.zeros(len(mass))
        for features, w, failed in episodes:
            if failed and site in features:
                target[cell_index(features[site], len(mass))] += w
        target *= mass > 0
        if not target.sum() > 0:
            continue
        new = smoothing * target / target.sum() + (1 - smoothing) * old / old.sum()
        weights[site] = [round(float(x), 9) for x in new / new.sum()]
    return Proposal(weights, proposal.eps, proposal.law)


def failure_rate_step(proposal: Proposal, masses: dict[str, np.ndarray], episodes: list[tuple[dict, float, bool]],
                      sharpness: float = 2.0) -> Proposal:
    """Per site, weights proportional to each cell's spec mass times its failure rate to the power `sharpness`.

    The rate of a cell is (failures + 1) / (episodes + 2) over every episode so far that drew in
    it (a Beta(1, 1) prior: a cell never tried counts as even odds, so it is explored). Unlike
    the cross-entropy step it follows where failures are *frequent*, not where their
    weighted mass lies, and a site the outcome does not depend on keeps near-equal rates and
    so stays near the spec's law."""
    weights = dict(proposal.weights)
    for site, mass in masses.items():
        tried, failed = np.zeros(len(mass)), np.zeros(len(mass))
        for features, _, fail in episodes:
            if site in features:
                cell = cell_index(features[site], len(mass))
                tried[cell] += 1
                failed[cell] += fail
        if not failed.sum() > 0:
            continue
        new = mass * ((failed + 1) / (tried + 2)) ** sharpness
        weights[site] = [round(float(x), 9) for x in new / new.sum()]
    return Proposal(weights, proposal.eps, proposal.law)
