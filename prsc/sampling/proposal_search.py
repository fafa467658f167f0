"""How a falsification proposal learns from the episodes so far: a failure-rate tree, or cross-entropy.

Each step maps (the current proposal, the cells' spec masses by site, the episodes so far as
Episodes) to the next round's proposal (prsc/sampling/proposal.py). The
*elite* episodes are those the next round leans toward (near_failures): the failures, or,
steered by robustness, every episode at or below an adaptive level of robustness that falls
to 0 (multilevel cross-entropy). The conditional elite rate does not depend on the proposal
the episodes came from, so the tree uses every episode unweighted (docs/falsify.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple, Sequence

import numpy as np

from prsc.sampling.proposal import DEFAULT_EPS, SITE_EPS, Component, Proposal
from prsc.sampling.proposal_cells import fine_k, grid_index

ELITE_QUANTILE = 0.1  # multilevel cross-entropy: the share of the episodes so far under the next level
MIN_ELITE = 4  # ... and at least this many episodes
SHARPNESS = 4.0  # a near failure's pull: exp(-SHARPNESS robustness / level), e**-4 at the level, 1 at 0
STAY = 0.5  # a near failure's replay: this share in its own fine cell, the rest in the neighbouring fine cells


def elite_level(robustness: Sequence[float | None], quantile: float = ELITE_QUANTILE, least: int = MIN_ELITE) -> float:
    """The robustness level of the next round: max(0, the `quantile` of the known robustness, at least `least` under it).

    Rubinstein's multilevel cross-entropy for rare events: the target of a round is the spec's
    law restricted to {robustness <= level}, and the level falls with the rounds until it
    reaches 0, where that target is the failure set itself (docs/falsify.md)."""
    known = np.sort(np.array([r for r in robustness if r is not None], dtype=float))
    if not len(known):
        return 0.0
    rank = min(len(known) - 1, max(int(np.ceil(quantile * len(known))), least) - 1)
    return max(0.0, float(known[rank]))


def near_failures(failed: Sequence[bool], robustness: Sequence[float | None]) -> list[float]:
    """How much the next proposal leans toward each episode: 1 for a failure, exp(-SHARPNESS robustness / level)
    for an episode at or below the robustness level, 0 for the others.

    With no robustness known (None: steered by the labels alone) the elite are the failures."""
    if all(r is None for r in robustness):
        return [float(f) for f in failed]
    level = elite_level(robustness)
    return [1.0 if f or (r is not None and r <= 0) else
            float(np.exp(-SHARPNESS * r / level)) if r is not None and r <= level else 0.0 for f, r in zip(failed, robustness)]


class Episode(NamedTuple):
    """One episode as the search sees it: where its draws fell, its importance weight, and how it counts."""

    features: dict[str, list[float]]
    weight: float
    elite: float  # how much the next proposal leans toward it (near_failures: 1 a failure, 0 not at all)
    failed: bool  # a failure is replayed in its own fine cells, a near failure around them


def cell_index(coords: list[float], cells: int) -> int:
    """The cell of normalised coordinates on a grid of `cells` cells (cells per axis ** axes)."""
    k = int(round(cells ** (1.0 / max(len(coords), 1))))
    return grid_index(np.asarray(coords, dtype=float), k)


def _fine_cells(coords: list[float], mass: np.ndarray, reach: int) -> dict[int, float]:
    """The fine cell holding `coords` and, with reach 1, those one fine step from it on any axis.

    The own cell weighs 1 (reach 0) or STAY, the others share the rest."""
    dims = len(coords)
    k = fine_k(_per_axis(mass, dims), dims)
    centre = [min(int(x * k), k - 1) for x in coords]
    own = int(np.ravel_multi_index(centre, (k,) * dims))
    others = []
    for offset in np.ndindex(*(2 * reach + 1,) * dims):
        digits = [c + o - reach for c, o in zip(centre, offset)]
        if all(0 <= d < k for d in digits) and digits != centre:
            others.append(int(np.ravel_multi_index(digits, (k,) * dims)))
    if not others:
        return {own: 1.0}
    return {own: STAY, **{c: (1 - STAY) / len(others) for c in others}}


def cross_entropy_step(proposal: Proposal, masses: dict[str, np.ndarray], episodes: list[Episode],
                       smoothing: float = 0.7) -> Proposal:
    """One cross-entropy update toward the elite episodes: one product component.

    Per site the maximiser of sum over the elite of W log q is their importance-weighted
    share per cell; it is mixed with the current weights (`smoothing`, as VerifAI does) so no
    cell of positive mass ever gets weight zero. Each site keeps SITE_EPS of the spec's law."""
    old = proposal.components[0].cells if proposal.components else {}
    cells: dict[str, dict[int, float]] = {}
    for site, mass in masses.items():
        before = np.array([old[site].get(c, 0.0) for c in range(len(mass))]) if site in old else np.asarray(mass, float)
        target = np.zeros(len(mass))
        for features, w, elite, _ in episodes:
            if elite and site in features:
                target[cell_index(features[site], len(mass))] += w * elite
        target *= mass > 0
        if not target.sum() > 0 or not before.sum() > 0:
            if site in old:
                cells[site] = old[site]
            continue
        new = smoothing * target / target.sum() + (1 - smoothing) * before / before.sum()
        cells[site] = {c: round(float(x), 9) for c, x in enumerate(new / new.sum()) if x > 0}
    return Proposal((Component(1.0, SITE_EPS, cells),) if cells else (), DEFAULT_EPS, proposal.law)


def replay_components(masses: dict[str, np.ndarray], episodes: list[Episode],
                      spec_share: float = 0.0) -> list[Component]:
    """One component per elite episode: every site redrawn in the fine cell a failure drew, or around the fine
    cell a near failure drew (a step toward failing; spec_share: the spec's law)."""
    return [Component(elite, spec_share, {}, {site: _fine_cells(coords, masses[site], 0 if failed else 1)
                                              for site, coords in features.items() if site in masses})
            for features, _, elite, failed in episodes if elite]


@dataclass(frozen=True)
class Leaf:
    """A box of the inputs: per (site, axis) a half-open range of grid digits; its episodes and failures."""

    bounds: dict[tuple[str, int], tuple[int, int]]
    episodes: int
    failures: int


def _per_axis(mass: np.ndarray, dims: int) -> int:
    """Grid cells per axis of a site with len(mass) cells over `dims` axes."""
    return int(round(len(mass) ** (1.0 / max(dims, 1))))


def _digits(features: dict[str, list[float]], masses: dict[str, np.ndarray], sites: list[str]) -> list[int] | None:
    """An episode's grid digit per (site, axis) over `sites`, or None when it misses a site."""
    out = []
    for site in sites:
        coords = features.get(site)
        if coords is None:
            return None
        k = _per_axis(masses[site], len(coords))
        out += [min(int(x * k), k - 1) for x in coords]
    return out


def grow_tree(x: np.ndarray, y: np.ndarray, ks: list[int], min_leaf: int, depth: int) -> list[Leaf]:
    """Leaves of a classification tree on grid digits x (episodes, axes) and failures y (Gini splits at digit steps)."""
    def grow(rows: np.ndarray, bounds: dict[int, tuple[int, int]], level: int) -> list[tuple[dict, np.ndarray]]:
        best, n = None, len(rows)
        if level < depth and n >= 2 * min_leaf:
            f = y[rows].sum()
            impurity = f * (n - f) / n
            for axis, k in enumerate(ks):
                lo, hi = bounds.get(axis, (0, k))
                for cut in range(lo + 1, hi):
                    left = x[rows, axis] < cut
                    nl = int(left.sum())
                    if nl < min_leaf or n - nl < min_leaf:
                        continue
                    fl = y[rows][left].sum()
                    fr = f - fl
                    gain = impurity - fl * (nl - fl) / nl - fr * (n - nl - fr) / (n - nl)
                    if best is None or gain > best[0] + 1e-12:
                        best = (gain, axis, cut, left)
        if best is None or best[0] <= 1e-9:
            return [(bounds, rows)]
        _, axis, cut, left = best
        lo, hi = bounds.get(axis, (0, ks[axis]))
        return (grow(rows[left], {**bounds, axis: (lo, cut)}, level + 1)
                + grow(rows[~left], {**bounds, axis: (cut, hi)}, level + 1))

    return [Leaf(b, len(r), int(y[r].sum())) for b, r in grow(np.arange(len(y)), {}, 0)]  # type: ignore[arg-type]


def _leaf_rate(leaves: list[Leaf], rates: list[float], digits: list[int] | None, overall: float) -> float:
    """The failure rate of the leaf holding an episode's grid digits (the overall rate when it misses a site)."""
    for leaf, rate in zip(leaves, rates):
        if digits is not None and all(lo <= digits[a] < hi for a, (lo, hi) in leaf.bounds.items()):
            return rate
    return overall


def failure_tree_step(proposal: Proposal, masses: dict[str, np.ndarray], episodes: list[Episode],
                      sharpness: float = 0.5, min_leaf: int = 8, depth: int = 5, replay: float = 0.7,
                      replay_spec_share: float = 0.0, replay_focus: float = 1.0) -> Proposal:
    """A mixture over the leaves of a failure-rate tree (share ∝ spec mass × rate ** sharpness) and the failures found.

    "Failure" here is an elite episode (near_failures): steered by robustness, the near
    failures count too, with their pull, until the level reaches 0.

    The tree splits the inputs (every site's grid digits) where the failure rate changes, so a
    failure mode that needs two inputs at once (the cube in its tray's front *and* the tray in
    the camera's far corner) is one leaf; inside a leaf every site keeps the spec's law
    restricted to the leaf's cells. With sharpness 1/2 that part is the spec's law times the
    square root of the failure rate, the importance law of least variance for the failure
    probability (q ∝ p sqrt(rate)): it leans toward failures without thinning the bulk of
    the inputs, where a controller with diffuse failures has half its failure probability.
    A leaf's rate is shrunk toward the overall one (a Beta prior of 2 episodes). The
    `replay` share of the mixture redraws near the failures found (replay_components), each
    failure in proportion to its leaf's rate ** replay_focus (a failure in a leaf that
    mostly fails is a mode, one in a leaf that mostly succeeds is likely noise): it finds
    the most failures, but its scenes weigh almost nothing in the estimate. The defaults
    were chosen on surrogate controllers (docs/falsify.md)."""
    sites = sorted(masses)
    rows = [(d, elite > 0) for features, _, elite, _ in episodes
            if (d := _digits(features, masses, sites)) is not None]
    if not rows or not any(f for _, f in rows):
        return proposal
    x = np.array([d for d, _ in rows], dtype=int)
    y = np.array([f for _, f in rows], dtype=float)
    dims = {site: len(next(e.features[site] for e in episodes if site in e.features)) for site in sites}
    axes = [(site, a) for site in sites for a in range(dims[site])]
    ks = [_per_axis(masses[site], dims[site]) for site, _ in axes]
    overall = float(y.mean())
    components = []
    leaves = grow_tree(x, y, ks, min_leaf, depth)
    rates = [(leaf.failures + 2 * overall) / (leaf.episodes + 2) for leaf in leaves]
    for leaf, rate in zip(leaves, rates):
        cells: dict[str, dict[int, float]] = {}
        share = 1.0
        for site in sorted({axes[a][0] for a in leaf.bounds}):
            k = _per_axis(masses[site], dims[site])
            ranges = [leaf.bounds.get(axes.index((site, a)), (0, k)) for a in range(dims[site])]
            inside = {c: float(m) for c, m in enumerate(masses[site]) if m > 0 and all(
                lo <= d < hi for d, (lo, hi) in zip(np.unravel_index(c, (k,) * dims[site]), ranges))}
            share *= sum(inside.values())
            cells[site] = inside
        components.append(Component(share * rate ** sharpness, 0.0, cells))
    if replay > 0:
        total = sum(c.share for c in components)
        kernels = replay_components(masses, episodes, replay_spec_share)
        focus = np.array([_leaf_rate(leaves, rates, _digits(features, masses, sites), overall) ** replay_focus
                          for features, _, elite, _ in episodes if elite])
        focus *= [c.share for c in kernels]
        components += [Component(replay / (1 - replay) * total * f / focus.sum(), c.spec_share, c.cells, c.fine)
                       for c, f in zip(kernels, focus)]
    return Proposal(tuple(components), DEFAULT_EPS, proposal.law)
