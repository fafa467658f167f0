from __future__ import annotations


import numpy as np
import pytest

from prsc.geometry.boxes import Box
from prsc.geometry.iis import irreducible_infeasible_subset, is_feasible
from prsc.geometry.polytope import NO_LABEL, Polytope, intersect


def _scene():
    table = Polytope.from_box(Box([0, 0, 0.5], np.eye(3), [1, 1, 0.5]), label=0)
    return [
        table,
        Polytope.halfspace([0, 1, 0], 0.5, label=1),  # y <= 0.5 (harmless)
        Polytope.halfspace([0, 0, -1], -0.2, label=2),  # z >= 0.2 (harmless)
        Polytope.halfspace([-1, 0, 0], -2.0, label=3),  # x >= 2: conflicts with the table
        Polytope.halfspace([1, 1, 0], 1.9, label=4),  # harmless
    ]


def test_iis_names_the_conflicting_pair():
    assert irreducible_infeasible_subset(intersect(*_scene())) == (0, 3)


def test_iis_needs_three_labels_together():
    p = intersect(
        Polytope.halfspace([1, 0, 0], 1.0, label=10),
        Polytope.halfspace([0, 1, 0], 1.0, label=11),
        Polytope.halfspace([-1, -1, 0], -2.5, label=12),
        Polytope.halfspace([0, 0, 1], 5.0, label=13),
    )
    assert irreducible_infeasible_subset(p) == (10, 11, 12)


def test_iis_with_equalities_and_background_rows():
    bg = Polytope.from_box(Box([0, 0, 0], np.eye(3), [1, 1, 1]))  # NO_LABEL background
    p = intersect(bg, Polytope.plane([0, 0, 1], 1.5, label=5), Polytope.halfspace([1, 0, 0], 0.0, label=6))
    assert bg.labels[0] == NO_LABEL
    assert irreducible_infeasible_subset(p) == (5,)


def test_feasible_raises():
    p = intersect(*_scene()[:3])
    assert is_feasible(p)
    with pytest.raises(ValueError):
        irreducible_infeasible_subset(p)


def test_iis_is_minimal_on_random_systems():
    rng = np.random.default_rng(0)
    for _ in range(20):
        n = rng.normal(size=(15, 3))
        p = Polytope.from_rows(n, rng.normal(size=15) - 0.5, labels=np.arange(15))
        if is_feasible(p):
            continue
        core = irreducible_infeasible_subset(p)
        sub = lambda labs: Polytope.from_rows(n[list(labs)], p.b[list(labs)], labels=list(labs))
        assert not is_feasible(sub(core))
        for lab in core:
            assert is_feasible(sub([c for c in core if c != lab]))
