"""Irreducible infeasible subset (IIS) of labelled constraint rows, by a deletion filter.

Rows are grouped by label (a label is one specifier or source span); rows labelled
NO_LABEL are background that is always kept and never reported. For each label in turn,
drop its rows; if the rest is still infeasible the label is not needed, else it is put
back. What remains is minimal: removing any one label makes the system feasible. Each
test is one warm-started HiGHS LP (the Chebyshev margin, see lp.MarginModel).

Feasibility here means the Chebyshev margin is >= -tol: every row can be met to within
tol metres at one point, the same tolerance the sampler's emptiness test uses.
"""

from __future__ import annotations

import numpy as np

from prsc.geometry.affine import TOL
from prsc.geometry.lp import MarginModel, chebyshev_center
from prsc.geometry.polytope import NO_LABEL, Polytope


def is_feasible(poly: Polytope, tol: float = TOL) -> bool:
    """True if some point meets every row of `poly` to within tol (rows normalised)."""
    p = poly.normalized()
    return chebyshev_center(p.A, p.b, p.C, p.d)[1] >= -tol


def irreducible_infeasible_subset(poly: Polytope, tol: float = TOL) -> tuple[int, ...]:
    """Labels of a minimal infeasible set of labelled row groups (plus background rows).

    Raises ValueError if `poly` is feasible. Returns () if the background rows alone
    (NO_LABEL) are infeasible.
    """
    p = poly.normalized()
    model = MarginModel(p.A, p.b, p.C, p.d)
    keep_i = np.ones(len(p.b), bool)
    keep_e = np.ones(len(p.d), bool)
    if model.margin(keep_i, keep_e) >= -tol:
        raise ValueError("the constraints are feasible: there is no infeasible subset")
    order: list[int] = []
    for lab in np.concatenate([p.labels, p.eq_labels]).tolist():
        if lab != NO_LABEL and lab not in order:
            order.append(lab)
    needed: list[int] = []
    for lab in order:
        trial_i = keep_i & (p.labels != lab)
        trial_e = keep_e & (p.eq_labels != lab)
        if model.margin(trial_i, trial_e) < -tol:
            keep_i, keep_e = trial_i, trial_e  # still infeasible without it: drop for good
        else:
            needed.append(lab)
    return tuple(needed)
