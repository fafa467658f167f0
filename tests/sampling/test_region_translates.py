"""Gibbs sweeps reuse a region prepared earlier in the scene when new rows only translate
it (prsc/sampling/prepared_regions.py, `_Translatable`): a part's region in a bin that moved.

- rows whose tight rows move by t, with far workspace rows that stay slack, give the
  prepared region plus t: the same vertices as a fresh preparation, the same measure;
- a workspace row that would cut the translated region, or rows that change shape (a
  wall moved alone), are not reused;
- on bin_picking the sweeps do reuse preparations, each with the bounds of a fresh one
  (tests/sampling/test_scene_checks.py checks every relation of its joint-law scenes).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import prsc.sampling.prepared_regions as regions
from prsc.geometry.polytope import Polytope
from prsc.sampling import compile_sampler
from prsc.sampling.prepared import prepare
from prsc.sampling.prepared_regions import _Translatable

REPO = Path(__file__).resolve().parents[2]


def _part_in_bin(centre: np.ndarray, workspace: float = 2.5) -> Polytope:
    """A part's rows in a bin at `centre`: inner walls 0.15 x 0.1 about it, its floor height,
    and a workspace's walls at `workspace` m (rows that do not move with the bin)."""
    walls = np.array([[1.0, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0]])
    half = np.array([0.15, 0.15, 0.1, 0.1])
    workspace_rows = np.vstack([np.eye(3), -np.eye(3)])
    return Polytope.from_rows(np.vstack([walls, workspace_rows]),
                              np.concatenate([half + walls @ centre, np.full(6, workspace)]),
                              C=[[0.0, 0, 1]], d=[centre[2]])


def _corners(prepared) -> set[tuple[float, ...]]:
    return {tuple(np.round(v, 9)) for v in prepared.sampler.vertices()}


def test_translated_rows_give_the_prepared_region_plus_the_shift():
    rng = np.random.default_rng(3)
    first = _part_in_bin(np.array([0.1, 0.2, 0.77]))
    known = _Translatable.of(first, prepare(first))
    assert known.tight.tolist() == [True] * 4 + [False] * 6  # the workspace walls are slack
    for _ in range(20):
        centre = np.array([0.1, 0.2, 0.77]) + rng.uniform(-0.5, 0.5, 3)
        moved = _part_in_bin(centre)
        shift = known.shift_to(moved)
        assert shift is not None
        np.testing.assert_allclose(shift, centre - [0.1, 0.2, 0.77], atol=1e-12)
        fresh = prepare(moved)
        translated = {tuple(np.round(np.array(v) + shift, 9)) for v in _corners(known.prepared)}
        assert translated == _corners(fresh)
        assert abs(known.prepared.measure - fresh.measure) < 1e-12


def test_a_cutting_workspace_row_or_a_moved_wall_is_not_reused():
    first = _part_in_bin(np.array([0.1, 0.2, 0.77]))
    known = _Translatable.of(first, prepare(first))
    assert known.shift_to(_part_in_bin(np.array([2.45, 0.2, 0.77]))) is None  # the workspace cuts it there
    wider = _part_in_bin(np.array([0.1, 0.2, 0.77]))
    wider = Polytope.from_rows(wider.A, wider.b + np.array([0.05, 0, 0, 0, 0, 0, 0, 0, 0, 0]), C=wider.C, d=wider.d)
    assert known.shift_to(wider) is None  # one wall moved: another shape
    lower = Polytope.from_rows(first.A, first.b, C=first.C, d=first.d - 0.1)
    shift = known.shift_to(lower)  # the floor moved down: a translate in z
    assert shift is not None and np.allclose(shift, [0, 0, -0.1])


def test_bin_picking_sweeps_reuse_preparations_with_the_fresh_regions_bounds(monkeypatch):
    reused = []
    translated = regions.RegionProvider._translated

    def counting(self, poly, ctx):
        prepared, shift = translated(self, poly, ctx)
        if shift is not None:
            reused.append(shift)
            fresh = prepare(poly)
            assert np.allclose(prepared.lo + shift, fresh.lo, atol=1e-9)
            assert np.allclose(prepared.hi + shift, fresh.hi, atol=1e-9)
        return prepared, shift

    monkeypatch.setattr(regions.RegionProvider, "_translated", counting)
    # batched=False: the Gibbs sweeps (by default candidate rounds draw bin_picking's joint law)
    sampler = compile_sampler(REPO / "specs" / "bin_picking.prs", batched=False)
    for index in range(3):
        sampler.scene(0, index)
    assert len(reused) > 50  # most sweeps' regions of the parts are translates
