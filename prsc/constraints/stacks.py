"""`stably on X`: a stack whose centres of mass stay over their supports, as exact rows.

The object rests on X as with `on X`, its centre over X's top face. When X itself stands
`stably on` Y, and so on down, then for each lower support A_k (Y, what Y stands on, ...)
the centre of mass of the object and the objects x_j between it and A_k (masses m_j,
centres p_j),

    (m p + sum_j m_j p_j) / (m + sum_j m_j),

must lie over the contact between A_k and the object standing on it: the overlap of A_k's
top face and that object's footprint. That is linear in p: eight rows per support. Every
face is shrunk by MARGIN. A tower built this way stands under gravity on level supports
(docs/language.md, "`stably on X`"). Masses are the constant `mass` property, else density
times box volume, centres of mass the box centres (a uniform box).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from prsc.constraints.specifier_rows import rows_on
from prsc.constraints.support import Support
from prsc.constraints.values import ObjectValue
from prsc.errors import PrscError, Span
from prsc.geometry.polytope import Polytope, intersect
from prsc.ir.builtins import default_mass

MARGIN = 0.25
"""Each face is shrunk by this fraction of its half-extents: a centre of mass right at an edge
balances in statics but tips under a simulator's soft contacts (measured in docs/language.md)."""

def object_mass(obj: ObjectValue) -> float:
    """The object's mass: its `mass` if a number, else density times its box volume."""
    mass = obj.props.get("mass")
    if isinstance(mass, (int, float)) and not isinstance(mass, bool) and mass > 0:
        return float(mass)
    assert obj.dims is not None
    return default_mass(*(float(d) for d in obj.dims))


def _face_rows(support: ObjectValue) -> tuple[np.ndarray, np.ndarray]:
    """Rows a . q <= c keeping q inside the object's face (its top or bottom) shrunk by MARGIN."""
    assert support.position is not None and support.rotation is not None and support.dims is not None
    u, v = support.rotation[:, 0], support.rotation[:, 1]
    a = np.stack([u, -u, v, -v])
    half = np.array([support.dims[0], support.dims[0], support.dims[1], support.dims[1]]) * 0.5
    return a, a @ support.position + half * (1.0 - MARGIN)


def _rows(face: tuple[np.ndarray, np.ndarray], mass: float, carried: np.ndarray, total: float, label: int) -> Polytope:
    """The centre of mass (mass p + carried) / total over the face: a . p <= (total c - a . carried) / mass."""
    a, c = face
    b = (total * c - a @ carried) / mass
    return Polytope(a, b, np.zeros((0, 3)), np.zeros(0), np.full(len(b), label), np.zeros(0, np.int64))


def rows_stably(chain: Sequence[Any], mass: float, support: Support, label: int, span: Span | None) -> Polytope:
    """`stably on X`: rows_on(X), and for each lower support in `chain` (X, Y, ...: each
    stably on the next) the centre of mass of the object and the objects above it in rows."""
    target = chain[0]
    rows = rows_on(target, False, support, label, span)
    if not isinstance(target, ObjectValue):
        return rows
    carried = np.zeros(3)  # sum of m_j p_j over the objects between the object and the support
    total = mass
    rows = intersect(rows, _rows(_face_rows(target), mass, carried, total, label))
    for above, below in zip(chain, chain[1:]):
        if above.position is None or above.dims is None or below.position is None:
            raise PrscError(f"{above.name} is not placed yet here", span)
        m = object_mass(above)
        carried = carried + m * above.position
        total += m
        # The contact between `above` and `below` is the overlap of above's footprint and
        # below's top face: the centre of mass must lie over both.
        rows = intersect(rows, _rows(_face_rows(below), mass, carried, total, label),
                         _rows(_face_rows(above), mass, carried, total, label))
    return rows
