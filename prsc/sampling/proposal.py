"""A proposal law over a spec's random inputs that only reweights its feasible set.

Every *site* (one object's position, one `(lo, hi)` range draw) is cut into cells: for a
position, a grid over the bounding box of the object's feasible region *in the scene at
hand* (cell c is the region cut by the grid box, prepared by the same exact sampler, so
every draw is inside the region); for a range, equal bins of its unit interval. Cells live
in the region's normalised coordinates, so "the corner of the tray" is the same cell
wherever the tray went. The proposal is a defensive mixture over whole scenes,

    q = eps * p + (1 - eps) * sum_k share_k * q_k,

each component q_k a product over sites of (spec_share * the spec's law + the rest on
weighted cells). A scene's importance weight under the *sequential* law (docs/sampling.md)
is p / q = 1 / (eps + (1 - eps) sum_k share_k prod_sites r_k), r_k the component's ratio
at the draw's cell (Component.site_ratio): at most 1 / eps (docs/falsify.md). A proposal
without components draws exactly as the spec's law does, draw for draw, with weight 1:
round 0 of a campaign is the scenes `prsc sample` draws.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from prsc.errors import PrscError
from prsc.geometry.polytope import Polytope
from prsc.geometry.uniform_sampling import UniformSampler
from prsc.sampling.proposal_cells import GRID, REFINE, Cells, fine_k, free_space_cells, grid_index, region_cells

FORMAT = "prsc-proposal/1"
DEFAULT_EPS = 0.1  # defensive share of the spec's own law: every scene's weight <= 1 / eps
SITE_EPS = 0.2  # cross-entropy: each site's share of the spec's law (every site's ratio <= 1 / SITE_EPS)
RANGE_BINS = 8
RANGE_MASS = np.full(RANGE_BINS, 1.0 / RANGE_BINS)


@dataclass(frozen=True)
class Component:
    """One product law over the sites: per site, `spec_share` of the spec's law, the rest on weighted cells
    (or on weighted fine cells: `fine`)."""

    share: float  # the component's share of the mixture
    spec_share: float
    cells: dict[str, dict[int, float]]  # site -> {cell: weight}; a site absent keeps the spec's law
    fine: dict[str, dict[int, float]] = field(default_factory=dict)  # site -> {fine cell: weight}, instead

    def weights(self, site: str) -> tuple[dict[int, float] | None, bool]:
        """The site's cell weights and whether they are fine cells (None: the site keeps the spec's law)."""
        if site in self.fine:
            return self.fine[site], True
        return self.cells.get(site), False

    def site_ratio(self, site: str, draw: Draw) -> float:
        """This component's density over the spec's at a site's draw."""
        weights, fine = self.weights(site)
        if weights is None:
            return 1.0
        if fine:
            return self._ratio(weights, draw.fine, draw.fine_mass)
        return self._ratio(weights, draw.cell, lambda c: float(draw.mass[c]) if 0 <= c < len(draw.mass) else 0.0)

    def _ratio(self, weights: dict[int, float], cell: int, mass_of: Callable[[int], float]) -> float:
        """spec_share + (1 - spec_share) (w_cell / the weights of cells of positive mass) / mass_of(cell)."""
        mass = mass_of(cell)
        if not mass > 0:
            return 1.0
        weight = weights.get(cell, 0.0)
        if not weight > 0 and any(w > 0 and mass_of(c) > 0 for c, w in weights.items()):
            return self.spec_share  # the component draws this site elsewhere (the usual case: no total needed)
        total = sum(w for c, w in weights.items() if mass_of(c) > 0)
        if not total > 0:
            return 1.0
        return self.spec_share + (1 - self.spec_share) * weight / total / mass

    def cell_ratio(self, site: str, cell: int, mass: np.ndarray, dims: int) -> float:
        """This component's marginal density over the spec's on a (coarse) cell of the site (for plots)."""
        weights, fine = self.weights(site)
        if weights is not None and fine:
            k = int(round(len(mass) ** (1.0 / max(dims, 1))))
            refine = REFINE[max(dims, 1)]
            coarse: dict[int, float] = {}
            for c, w in weights.items():
                digits = np.unravel_index(c, (k * refine,) * max(dims, 1))
                key = int(np.ravel_multi_index([d // refine for d in digits], (k,) * max(dims, 1)))
                coarse[key] = coarse.get(key, 0.0) + w
            weights = coarse
        if weights is None:
            return 1.0
        return self._ratio(weights, cell, lambda c: float(mass[c]) if 0 <= c < len(mass) else 0.0)

    def to_json(self) -> dict[str, Any]:
        """As DIR/proposal.json stores it."""
        out = {"share": self.share, "spec_share": self.spec_share,
               "cells": {site: {str(c): w for c, w in sorted(cells.items())} for site, cells in self.cells.items()}}
        if self.fine:
            out["fine"] = {site: {str(c): w for c, w in sorted(cells.items())} for site, cells in self.fine.items()}
        return out


@dataclass(frozen=True)
class Strata:
    """A round's systematic choice of components: scene start + j takes the point (offset + j) / count.

    Over the points, the spec's law and each component get count * share scenes up to one
    (share: eps, or (1 - eps) share_k), so the mixture weight p / q keeps the estimate unbiased
    while the groups' sizes no longer vary by chance (docs/falsify.md)."""

    start: int
    count: int
    offset: float  # in [0, 1), one uniform draw per round

    def point(self, index: int) -> float | None:
        """Scene `index`'s point in [0, 1), or None when it is outside the strata."""
        j = index - self.start
        return (self.offset + j) / self.count if 0 <= j < self.count else None


@dataclass(frozen=True)
class Proposal:
    """eps of the spec's law plus a mixture of product components (none: the spec's law, draw for draw)."""

    components: tuple[Component, ...] = ()
    eps: float = DEFAULT_EPS
    law: str = "sequential"
    strata: Strata | None = None  # a campaign round's systematic component choice (not stored)

    def to_json(self) -> dict[str, Any]:
        """The proposal as DIR/proposal.json stores it."""
        return {"format": FORMAT, "law": self.law, "eps": self.eps, "range_bins": RANGE_BINS,
                "grid": {str(k): v for k, v in GRID.items()}, "refine": {str(k): v for k, v in REFINE.items()},
                "components": [c.to_json() for c in self.components]}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> Proposal:
        """Read what to_json wrote."""
        if not isinstance(data, dict) or data.get("format") != FORMAT:
            raise PrscError(f"not a prsc proposal (expected \"format\": \"{FORMAT}\")")
        eps = float(data.get("eps", DEFAULT_EPS))
        if not 0.0 <= eps <= 1.0:
            raise PrscError(f"a proposal's eps must be in [0, 1], got {eps}")
        components = []
        for k, item in enumerate(data.get("components", [])):
            try:
                share, spec_share = float(item["share"]), float(item["spec_share"])
                cells = {str(site): {int(c): float(w) for c, w in ws.items()} for site, ws in item["cells"].items()}
                fine = {str(site): {int(c): float(w) for c, w in ws.items()} for site, ws in item.get("fine", {}).items()}
            except (KeyError, TypeError, ValueError, AttributeError):
                raise PrscError(f"proposal component {k}: expected share, spec_share and cells") from None
            weights = [w for ws in (*cells.values(), *fine.values()) for w in ws.values()]
            if not (share >= 0 and 0.0 <= spec_share <= 1.0) or any(w < 0 or not np.isfinite(w) for w in weights):
                raise PrscError(f"proposal component {k}: share, spec_share and weights must be >= 0 and finite "
                                "(spec_share <= 1)")
            components.append(Component(share, spec_share, cells, fine))
        if components and not sum(c.share for c in components) > 0:
            raise PrscError("a proposal's component shares must not all be 0")
        return cls(tuple(components), eps, str(data.get("law", "sequential")))

    def site_density(self, site: str, mass: np.ndarray, dims: int) -> np.ndarray:
        """Per cell of a site (over `dims` axes), the proposal's marginal density over the spec's (1 where it keeps
        the spec's law)."""
        if not self.components:
            return np.where(mass > 0, 1.0, 0.0)
        total = sum(c.share for c in self.components)
        mixed = sum(c.share / total * np.array([c.cell_ratio(site, k, mass, dims) for k in range(len(mass))])
                    for c in self.components)
        return np.where(mass > 0, self.eps + (1 - self.eps) * mixed, 0.0)

    def scene_state(self, index: int = -1) -> ProposalState:
        """The per-scene state a SceneContext carries while scene `index` is drawn."""
        return ProposalState(self, None if self.strata is None else self.strata.point(index))


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


@dataclass
class Draw:
    """One site's draw in a scene: where it fell (normalised coordinates), its cell and fine cell, and their spec masses."""

    coords: list[float]
    cell: int
    mass: np.ndarray
    fine: int
    fine_mass: Callable[[int], float]


RANGE_FINE = RANGE_BINS * REFINE[1]


def range_fine_mass(cell: int) -> float:
    """A range's fine bin's share of the spec's (uniform) law."""
    return 1.0 / RANGE_FINE if 0 <= cell < RANGE_FINE else 0.0


class ProposalState:
    """The draws of one scene under a proposal: (site, level) -> Draw, forgotten on a backtrack."""

    def __init__(self, proposal: Proposal, point: float | None = None) -> None:
        self.proposal = proposal
        self.point = point  # the scene's systematic point in [0, 1) (Strata), or None: drawn at random
        self.draws: dict[tuple[str, int], Draw] = {}
        self.masses: dict[str, np.ndarray] = {}  # per site, the spec's mass of each cell (for fitting)
        self.component: Component | None = None
        self.chosen = not proposal.components  # no components: every site keeps the spec's law

    def rollback(self, level: int) -> None:
        """Forget the draws made while placing objects >= level (SceneContext.rollback)."""
        for key in [key for key in self.draws if key[1] >= level]:
            del self.draws[key]

    def weight(self) -> float:
        """The scene's importance weight p / q: q / p = eps + (1 - eps) sum_k share_k prod_sites ratio_k."""
        components = self.proposal.components
        if not components:
            return 1.0
        total = sum(c.share for c in components)
        mixed = 0.0
        for component in components:
            ratio = component.share / total
            for (site, _), draw in self.draws.items():
                ratio *= component.site_ratio(site, draw)
                if ratio == 0.0:  # the scene is outside this component (a replay elsewhere): no need for the rest
                    break
            mixed += ratio
        return 1.0 / (self.proposal.eps + (1 - self.proposal.eps) * mixed)

    def features(self) -> dict[str, list[float]]:
        """Where each site's draw fell (normalised coordinates), by site."""
        out: dict[str, list[float]] = {}
        for (site, level), draw in sorted(self.draws.items()):
            out[f"{site}@{level}" if site in out else site] = draw.coords
        return out

    def _choose(self, ctx: Any) -> Component | None:
        """The scene's component (drawn once, at its first site): None for the spec's law."""
        if not self.chosen:
            self.chosen = True
            components, eps = self.proposal.components, self.proposal.eps
            u = ctx.uniform() if self.point is None else self.point
            if u >= eps:
                shares = np.cumsum([c.share for c in components])
                v = ctx.uniform() if self.point is None else (u - eps) / (1 - eps)
                pick = int(np.searchsorted(shares, v * shares[-1], side="right"))
                self.component = components[min(pick, len(components) - 1)]
        return self.component

    def _pick(self, site: str, mass: np.ndarray, fine_mass: Callable[[int], float], ctx: Any) -> tuple[int, bool] | None:
        """The cell the scene's component draws this site from, and whether it is a fine one (None: the spec's law)."""
        component = self._choose(ctx)
        weights, fine = (None, False) if component is None else component.weights(site)
        if not weights:
            return None
        mass_of = fine_mass if fine else (lambda c: float(mass[c]) if 0 <= c < len(mass) else 0.0)
        cells = [c for c in weights if weights[c] > 0 and mass_of(c) > 0]
        if not cells or ctx.uniform() < component.spec_share:  # type: ignore[union-attr]
            return None
        shares = np.cumsum([weights[c] for c in cells])
        return cells[min(int(np.searchsorted(shares, ctx.uniform() * shares[-1], side="right")), len(cells) - 1)], fine

    def position(self, name: str, level: int, region: Any, ctx: Any) -> np.ndarray:
        """A position drawn from the proposal on the prepared region (region coordinates)."""
        return self._cell_draw(f"position:{name}", level, region_cells(region), lambda: region.draw(ctx.rng, "exact", 1), ctx)

    def free_position(self, name: str, level: int, free: UniformSampler, region: Any, obstacles: list[Polytope],
                      ctx: Any) -> np.ndarray:
        """A position drawn from the proposal on a static free space (region minus obstacles)."""
        return self._cell_draw(f"position:{name}", level, free_space_cells(free, region, obstacles),
                               lambda: free.sample_one(ctx.rng), ctx)

    def _cell_draw(self, site: str, level: int, cells: Cells | None, spec_draw: Callable[[], np.ndarray],
                   ctx: Any) -> np.ndarray:
        """A point from the scene's component on the site's cells (spec_draw: one draw of the spec's law)."""
        if cells is None:  # a point: nothing to reweight
            return spec_draw()
        self.masses[site] = cells.mass
        picked = self._pick(site, cells.mass, cells.fine_mass, ctx)
        piece = None if picked is None else cells.fine_sampler(picked[0]) if picked[1] else cells.samplers[picked[0]]
        p = spec_draw() if piece is None else piece.sample_one(ctx.rng)
        u = cells.coords(p)
        self.draws[(site, level)] = Draw([round(float(x), 6) for x in u], grid_index(u, cells.k), cells.mass,
                                         grid_index(u, fine_k(cells.k, len(cells.axes))), cells.fine_mass)
        return p

    def spec_position(self, name: str, level: int) -> None:
        """The object's position came from the spec's own law (ratio 1): forget an earlier proposal draw."""
        self.draws.pop((f"position:{name}", level), None)

    def unit(self, site: str, ctx: Any) -> float:
        """A draw on [0, 1) for a range at `site` (spec law: uniform)."""
        site = f"range:{site}"
        self.masses[site] = RANGE_MASS
        picked = self._pick(site, RANGE_MASS, range_fine_mass, ctx)
        u = ctx.uniform()
        if picked is not None:
            u = (picked[0] + u) / (RANGE_FINE if picked[1] else RANGE_BINS)
        self.draws[(site, ctx.level)] = Draw([round(u, 6)], grid_index(np.array([u]), RANGE_BINS), RANGE_MASS,
                                             grid_index(np.array([u]), RANGE_FINE), range_fine_mass)
        return u
