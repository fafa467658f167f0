"""Small dense linear programs through HiGHS (highspy) directly.

scipy's `linprog` costs about 1 ms per call in wrapper overhead; the direct call solves
the sampler's LPs (3-10 variables, 6-60 rows) in about 0.1 ms. One solver object is kept
per thread.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass

import highspy
import numpy as np
from numpy.typing import ArrayLike, NDArray

from prsc.geometry.exceptions import GeometryError

_INF = highspy.kHighsInf
_ROWWISE = 2
_MINIMIZE = 1
_local = threading.local()
# Rows shorter than this are treated as constants (0 . x <= b).
_ZERO_ROW = 1e-12

_OPTIONS = (
    ("output_flag", False),
    ("presolve", "off"),  # the LPs are tiny; presolve costs more than it saves
    ("solver", "simplex"),
    ("threads", 1),
    ("primal_feasibility_tolerance", 1e-10),
    ("dual_feasibility_tolerance", 1e-10),
)


def _solver() -> highspy._core._Highs:
    """The calling thread's HiGHS instance (created once)."""
    h = getattr(_local, "highs", None)
    if h is None:
        h = highspy._core._Highs()
        for key, value in _OPTIONS:
            h.setOptionValue(key, value)
        _local.highs = h
    return h


@dataclass(frozen=True)
class LpSolution:
    """Result of `solve_lp`: status is 'optimal', 'infeasible' or 'unbounded'."""

    status: str
    x: NDArray[np.float64]
    objective: float


def solve_lp(
    cost: ArrayLike,
    rows: ArrayLike,
    row_lower: ArrayLike,
    row_upper: ArrayLike,
    col_lower: ArrayLike | None = None,
    col_upper: ArrayLike | None = None,
) -> LpSolution:
    """Minimise cost . x subject to row_lower <= rows @ x <= row_upper and column bounds."""
    c = np.ascontiguousarray(cost, dtype=float)
    n = c.shape[0]
    m_rows = np.ascontiguousarray(rows, dtype=float).reshape(-1, n)
    m = m_rows.shape[0]
    # kHighsInf is IEEE infinity, so +-np.inf bounds pass through unchanged.
    lo = np.full(n, -_INF) if col_lower is None else np.asarray(col_lower, dtype=float)
    hi = np.full(n, _INF) if col_upper is None else np.asarray(col_upper, dtype=float)
    rl = np.asarray(row_lower, dtype=float)
    ru = np.asarray(row_upper, dtype=float)
    h = _solver()
    h.clearModel()
    h.passModel(
        n, m, m * n, _ROWWISE, _MINIMIZE, 0.0, c, lo, hi, rl, ru,
        np.arange(0, m * n, n, dtype=np.int32) if m else np.zeros(0, dtype=np.int32),
        np.tile(np.arange(n, dtype=np.int32), m),
        m_rows.ravel(),
        np.zeros(n, dtype=np.int32),
    )
    h.run()
    status = h.getModelStatus()
    ms = highspy.HighsModelStatus
    if status == ms.kOptimal:
        sol = h.getSolution()
        return LpSolution("optimal", np.array(sol.col_value), float(h.getInfo().objective_function_value))
    if status == ms.kInfeasible:
        return LpSolution("infeasible", np.full(n, np.nan), np.inf)
    if status in (ms.kUnbounded, ms.kUnboundedOrInfeasible):
        return LpSolution("unbounded", np.full(n, np.nan), -np.inf)
    raise GeometryError(f"HiGHS failed on a {m}x{n} LP: {h.modelStatusToString(status)}")


def chebyshev_center(
    a: ArrayLike,
    b: ArrayLike,
    c: ArrayLike | None = None,
    d: ArrayLike | None = None,
    radius_cap: float = 1e6,
) -> tuple[NDArray[np.float64], float]:
    """Centre x and radius r of the largest ball in {a x <= b, c x = d}, r capped above.

    r < 0 means the set is empty: r is then minus the smallest uniform violation
    (distance) by which every row can be met at once. Equality rows enter as a pair of
    inequalities, so r <= 0 whenever there are any; r = 0 then means feasible.
    """
    a = np.asarray(a, dtype=float)
    dim = a.shape[1]
    b = np.asarray(b, dtype=float).reshape(-1)
    if c is not None and len(c):
        c = np.asarray(c, dtype=float).reshape(-1, dim)
        d = np.asarray(d, dtype=float).reshape(-1)
        a = np.vstack([a, c, -c])
        b = np.concatenate([b, d, -d])
    norms = np.linalg.norm(a, axis=1)
    constant = norms < _ZERO_ROW
    if constant.any():
        # 0 . x <= b: no ball helps a violated constant row; an empty set, infinitely far.
        if np.any(b[constant] < -_ZERO_ROW):
            return np.zeros(dim), -np.inf
        a, b, norms = a[~constant], b[~constant], norms[~constant]
    rows = np.empty((a.shape[0], dim + 1))
    rows[:, :dim] = a
    rows[:, dim] = norms
    cost = np.zeros(dim + 1)
    cost[dim] = -1.0
    col_upper = np.full(dim + 1, np.inf)
    col_upper[dim] = radius_cap
    sol = solve_lp(cost, rows, np.full(len(b), -np.inf), b, None, col_upper)
    if sol.status != "optimal":  # cannot happen: always feasible, r bounded above
        raise GeometryError(f"Chebyshev LP ended {sol.status}")
    return sol.x[:dim], float(sol.x[dim])


class MarginModel:
    """The Chebyshev-margin LP of fixed rows, re-solved (warm) for subsets of them.

    For deletion filters: switching rows off is a bound change on a loaded model, and
    HiGHS restarts from the previous basis, several times faster than a fresh solve.
    """

    def __init__(
        self, a: ArrayLike, b: ArrayLike, c: ArrayLike | None = None, d: ArrayLike | None = None,
        radius_cap: float = 1e6,
    ) -> None:
        a = np.asarray(a, dtype=float)
        dim = a.shape[1]
        b = np.asarray(b, dtype=float).reshape(-1)
        c = np.zeros((0, dim)) if c is None else np.asarray(c, dtype=float).reshape(-1, dim)
        d = np.zeros(0) if d is None else np.asarray(d, dtype=float).reshape(-1)
        self._m, self._k = a.shape[0], c.shape[0]
        rows = np.vstack([a, c, -c])
        self._upper = np.concatenate([b, d, -d])
        norms = np.linalg.norm(rows, axis=1)
        self._constant = norms < _ZERO_ROW
        lp_rows = np.empty((rows.shape[0], dim + 1))
        lp_rows[:, :dim] = rows
        lp_rows[:, dim] = norms
        n = dim + 1
        cost = np.zeros(n)
        cost[dim] = -1.0
        col_upper = np.full(n, _INF)
        col_upper[dim] = radius_cap
        self._h = highspy._core._Highs()
        for key, value in _OPTIONS:
            self._h.setOptionValue(key, value)
        m = rows.shape[0]
        # Constant rows stay in the model switched off; they are judged without the LP.
        upper = np.where(self._constant, _INF, self._upper)
        self._h.passModel(
            n, m, m * n, _ROWWISE, _MINIMIZE, 0.0, cost, np.full(n, -_INF), col_upper,
            np.full(m, -_INF), upper,
            np.arange(0, m * n, n, dtype=np.int32), np.tile(np.arange(n, dtype=np.int32), m),
            lp_rows.ravel(), np.zeros(n, dtype=np.int32),
        )
        self._index = np.arange(m, dtype=np.int32)

    def margin(self, active_ineq: NDArray[np.bool_], active_eq: NDArray[np.bool_]) -> float:
        """Chebyshev margin (see chebyshev_center) of the active rows only."""
        active = np.concatenate([active_ineq, active_eq, active_eq])
        if np.any(active & self._constant & (self._upper < -_ZERO_ROW)):
            return -np.inf
        upper = np.where(active & ~self._constant, self._upper, _INF)
        h = self._h
        h.changeRowsBounds(len(upper), self._index, np.full(len(upper), -_INF), upper)
        h.run()
        if h.getModelStatus() != highspy.HighsModelStatus.kOptimal:
            raise GeometryError(f"margin LP ended {h.modelStatusToString(h.getModelStatus())}")
        return -float(h.getInfo().objective_function_value)
