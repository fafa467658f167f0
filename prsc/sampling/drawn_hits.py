"""Which proposals of a drawn box meet a partner's box, for many scenes at once (group_gibbs.py's
updates of objects whose size or yaw changes between scenes; docs/sampling.md, "Gibbs rounds").

A proposal meets a partner when their boxes collide as collisions.collide_pairs decides it: the
axis-aligned boxes overlap by more than the contact tolerance on every world axis, and the
smallest overlap over the SAT axes exceeds it too. For two upright boxes (both only yaw) most
pairs are decided without the SAT, from two circles about each box's centre in the plane:
- the SAT's horizontal overlap of two upright boxes is their penetration depth, which is at
  least that of the circles they contain (radius: the smaller horizontal half extent) and at
  most that of the circles containing them (radius: the half diagonal), so a pair whose
  inscribed circles overlap by more than the tolerance collides (when their heights do), and a
  pair whose circumscribed circles overlap by less does not;
- both bounds hold with a margin far above rounding (`MARGIN`), so the pairs left to the SAT are
  exactly those it would decide differently from the circles, and every decision is the SAT's.
A proposal that surely meets one partner is not tested against the others. Where, in every scene, all
heights overlap by more than the tolerance plus 2 * MARGIN (parts on one floor: `_level`, from their
extremes), no pair's height is tested, since every test would pass.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from prsc.geometry.obb import CONTACT_TOL, pair_overlaps, upright_overlaps

MARGIN = 1e-9  # metres: the circles decide only with this margin over rounding (scenes are ~1e-1 m, rounding ~1e-17 m)


@dataclass(frozen=True)
class Partners:
    """A drawn box's partners in each scene, stacked: centres, reaches (m, P, 3), and the radii of the circles
    each contains and is contained in (m, P), which every pair reads; half extents (m, Q, 3) and rotations
    (m, Q, 3, 3), which only the SAT's few pairs read, of the stack the partners were taken from (the partner
    p's are column `pick[p]`: taking partners copies none of them)."""

    positions: np.ndarray
    reaches: np.ndarray
    halves: np.ndarray
    rotations: np.ndarray
    inner: np.ndarray
    outer: np.ndarray
    pick: np.ndarray

    @classmethod
    def of(cls, positions: np.ndarray, reaches: np.ndarray, halves: np.ndarray, rotations: np.ndarray) -> "Partners":
        """The partners of stacked boxes, with their circles."""
        inner, outer = circles(halves)
        return cls(positions, reaches, halves, rotations, inner, outer, np.arange(positions.shape[1]))

    def rows(self, rows: np.ndarray) -> "Partners":
        """These scenes' partners."""
        return Partners(self.positions[rows], self.reaches[rows], self.halves[rows], self.rotations[rows],
                        self.inner[rows], self.outer[rows], self.pick)

    def columns(self, columns: tuple[int, ...]) -> "Partners":
        """These boxes of every scene (of a stack of every object's box: one object's partners)."""
        pick = list(columns)
        return Partners(self.positions[:, pick], self.reaches[:, pick], self.halves, self.rotations,
                        self.inner[:, pick], self.outer[:, pick], self.pick[pick])

    def refresh(self, k: int, position: np.ndarray, own: tuple[np.ndarray, np.ndarray, np.ndarray] | None) -> None:
        """Box k of the stack (as `of` made it) moved to `position` (m, 3), and, for a drawn box, took these
        rotations, half extents and reaches (`own`, one row per scene)."""
        self.positions[:, k] = position
        if own is not None:
            self.rotations[:, k], self.halves[:, k], self.reaches[:, k] = own
            self.inner[:, k], self.outer[:, k] = circles(own[1])


def circles(halves: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Radii of the circles an upright box of these half extents contains and is contained in, in the plane."""
    return np.minimum(halves[..., 0], halves[..., 1]), np.hypot(halves[..., 0], halves[..., 1])


def _level(heights: np.ndarray, reaches: np.ndarray, partner_heights: np.ndarray, partner_reaches: np.ndarray) -> bool:
    """Whether in every scene each proposal's heights (centres (m, s) and reaches) overlap each partner's ((m, P))
    by more than the tolerance plus 2 * MARGIN: |a - b| < ra + rb - t holds for every pair when the highest
    bottom of one side lies below the lowest top of the other less t, both ways (a NaN fails it)."""
    slack = CONTACT_TOL + 2 * MARGIN
    bottoms, tops = heights - reaches, heights + reaches
    partner_bottoms, partner_tops = partner_heights - partner_reaches, partner_heights + partner_reaches
    if bottoms.max() < partner_tops.min() - slack and partner_bottoms.max() < tops.min() - slack:
        return True  # over all scenes at once (a floor at the same height in each): 4 reductions of one number
    return bool((bottoms.max(axis=1) < partner_tops.min(axis=1) - slack).all()
                and (partner_bottoms.max(axis=1) < tops.min(axis=1) - slack).all())


def drawn_hits(centres: np.ndarray, rotations: np.ndarray, halves: np.ndarray, reaches: np.ndarray, live: np.ndarray,
               others: Partners, upright: bool) -> np.ndarray:
    """Which live proposals (m, s, ...: s per scene) collide with a partner's box in their scene: one broad phase
    over every (proposal, partner) pair (with the circles where all are upright), one SAT call for the pairs left."""
    hit = np.zeros(live.shape, dtype=bool)
    positions = others.positions
    if not positions.shape[1]:
        return hit
    every = bool(live.all())  # then no mask of the live proposals is taken over every pair
    if upright:
        # Over every pair, only the plane's distances where, in every scene, each proposal's heights overlap each
        # partner's by more than the tolerance (all stand on one floor): `_level` decides that from their
        # extremes with 2 * MARGIN over rounding, so each pair's height tests would pass; elsewhere they run.
        level = _level(centres[:, :, 2], reaches[:, :, 2], positions[:, :, 2], others.reaches[:, :, 2])
        gaps = [centres[:, :, None, axis] - positions[:, None, :, axis] for axis in range(2 if level else 3)]
        inner, outer = circles(halves)
        apart = gaps[0] * gaps[0]
        apart += gaps[1] * gaps[1]
        np.sqrt(apart, out=apart)
        # The circles decide with MARGIN over rounding, so their constants are folded into each proposal's
        # numbers (one operation fewer over every pair): the order of the additions changes no decision.
        # Their height test (with MARGIN) implies the exact one, which the pairs left take below.
        sure = apart < (inner - (CONTACT_TOL + MARGIN))[:, :, None] + others.inner[:, None, :]
        if not level:
            high = np.abs(gaps[2], out=gaps[2])
            sure &= high < (reaches[:, :, 2] - (CONTACT_TOL + MARGIN))[:, :, None] + others.reaches[:, None, :, 2]
        if not every:
            sure &= live[:, :, None]
        hit = sure.any(axis=2)
        close = apart < (outer - (CONTACT_TOL - MARGIN))[:, :, None] + others.outer[:, None, :]
        close &= ~(hit if every else hit | ~live)[:, :, None]
        scene, proposal, partner = np.nonzero(close)
        # The broad phase on the few pairs left: heights, then the world axes (the same operations per pair).
        near = np.ones(len(scene), dtype=bool) if level else \
            high[scene, proposal, partner] < reaches[scene, proposal, 2] + others.reaches[scene, partner, 2] - CONTACT_TOL
        for axis in range(2):
            near &= np.abs(gaps[axis][scene, proposal, partner]) < \
                reaches[scene, proposal, axis] + others.reaches[scene, partner, axis] - CONTACT_TOL
        scene, proposal, partner = scene[near], proposal[near], partner[near]
    else:
        gaps = [centres[:, :, None, axis] - positions[:, None, :, axis] for axis in range(3)]  # (m, s, P) each
        # Axis by axis: a reduction over an axis of 3 costs more than the comparisons.
        tall = reaches[:, :, None, 2] + others.reaches[:, None, :, 2]
        close = np.abs(gaps[2]) < tall - CONTACT_TOL
        if not every:
            close &= live[:, :, None]
        for axis in range(2):
            close &= np.abs(gaps[axis]) < reaches[:, :, None, axis] + others.reaches[:, None, :, axis] - CONTACT_TOL
        scene, proposal, partner = np.nonzero(close)
    if not len(scene):
        return hit
    overlaps = upright_overlaps if upright else pair_overlaps
    pairs = overlaps(centres[scene, proposal], rotations[scene, proposal], halves[scene, proposal],
                     positions[scene, partner], others.rotations[scene, others.pick[partner]],
                     others.halves[scene, others.pick[partner]]) > CONTACT_TOL
    hit[scene[pairs], proposal[pairs]] = True
    return hit
