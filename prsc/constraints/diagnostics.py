"""Diagnostics shared by the compiler and the samplers: empty regions and numeric failures."""

from __future__ import annotations

import numpy as np

from prsc.constraints.polytope_ir import RowLabel
from prsc.errors import PrscError, Span
from prsc.geometry.exceptions import GeometryError
from prsc.geometry.iis import irreducible_infeasible_subset
from prsc.geometry.polytope import Polytope


def infeasible_error(
    labels: list[RowLabel] | tuple[RowLabel, ...], ids: tuple[int, ...], obj: str, span: Span | None, what: str,
    declarations: dict[str, Span] | None = None,
) -> PrscError:
    """The error for an empty region: names each conflicting specifier with its source line."""
    conflicting = [labels[i] for i in ids]
    if not conflicting:
        message = f"{what}: {obj} has no position inside the workspace"
    elif len(conflicting) == 1:
        message = f"{what}: no position of {obj} satisfies '{conflicting[0].text}'"
    else:
        names = ", ".join(f"'{lab.text}'" for lab in conflicting)
        message = f"{what}: no position of {obj} satisfies {names} together"
    notes: list[tuple[str, Span | None]] = []
    for lab in conflicting:
        owner = "" if lab.object == obj or not lab.object else f" (of {lab.object})"
        notes.append((f"conflicting: {lab.text}{owner}", lab.span))
    seen: set[str] = set()
    for lab in conflicting:
        for ref in lab.refs:
            if declarations and ref in declarations and ref not in seen:
                seen.add(ref)
                notes.append((f"{ref} is declared here", declarations[ref]))
    return PrscError(message, span, tuple(notes))


def explain_empty(
    labels: list[RowLabel] | tuple[RowLabel, ...], poly: Polytope, obj: str, span: Span | None, what: str,
    declarations: dict[str, Span] | None = None,
) -> PrscError:
    """An infeasibility error for rows `poly`, with an irreducible infeasible subset."""
    try:
        ids = irreducible_infeasible_subset(poly)
    except ValueError:
        ids = tuple(sorted({int(i) for i in np.concatenate([poly.labels, poly.eq_labels]) if i >= 0}))
    return infeasible_error(labels, ids, obj, span, what, declarations)


def numeric_failure(obj: str, span: Span | None, error: GeometryError) -> PrscError:
    """A solver failure on an object's rows as an error at the object.

    Seen with coordinates or sizes far beyond any scene (1e300 m): the LPs cannot be
    solved in floating point, which is the spec's doing, not a bug in prsc."""
    return PrscError(
        f"cannot place {obj}: its constraints could not be solved numerically ({error}); "
        "are its numbers (metres, radians) within a sensible range?", span,
    )
