from __future__ import annotations

import numpy as np
import pytest

from prsc.geometry.lp import chebyshev_center, solve_lp


def test_chebyshev_of_a_box():
    a = np.vstack([np.eye(3), -np.eye(3)])
    b = np.array([1.0, 2.0, 3.0, 1.0, 0.0, 1.0])  # x in [-1,1], y in [0,2], z in [-1,3]
    x, r = chebyshev_center(a, b)
    assert r == pytest.approx(1.0)
    assert x[0] == pytest.approx(0.0) and x[1] == pytest.approx(1.0)


def test_chebyshev_margin_of_an_empty_set_is_negative():
    # x <= 0 and x >= 1: best compromise violates each by 0.5.
    x, r = chebyshev_center([[1.0, 0.0], [-1.0, 0.0]], [0.0, -1.0])
    assert r == pytest.approx(-0.5)
    # A violated constant row.
    _, r = chebyshev_center([[0.0, 0.0]], [-1.0])
    assert r == -np.inf


def test_chebyshev_with_equalities_is_zero_when_feasible():
    x, r = chebyshev_center(np.vstack([np.eye(3), -np.eye(3)]), np.ones(6), [[0, 0, 1.0]], [0.5])
    assert r == pytest.approx(0.0, abs=1e-12)
    assert x[2] == pytest.approx(0.5)


def test_solve_lp_statuses():
    sol = solve_lp([1.0, 1.0], [[1.0, 1.0]], [2.0], [np.inf], [0, 0], [5, 5])
    assert sol.status == "optimal" and sol.objective == pytest.approx(2.0)
    assert solve_lp([1.0], [[1.0]], [2.0], [1.0]).status == "infeasible"
    assert solve_lp([-1.0], [[1.0]], [0.0], [np.inf]).status == "unbounded"
