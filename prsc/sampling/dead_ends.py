"""The error for a scene the sampler could not complete: where its last dead end was and why."""

from __future__ import annotations

from typing import Mapping, Sequence

from prsc.constraints.diagnostics import explain_empty
from prsc.constraints.polytope_ir import ObjectPlan, RowLabel
from prsc.errors import PrscError, Span
from prsc.sampling.attempt import Failure


def dead_end_error(labels: Sequence[RowLabel], plans: Sequence[ObjectPlan], declarations: Mapping[str, Span],
                   head: str, failure: Failure) -> PrscError:
    """The error after `head` (which scene, how many attempts, the rejections) for the last failure."""
    span: Span | None = None
    if 0 <= failure.index < len(plans):
        plan = plans[failure.index]
        span = plan.span
        head += f"; last dead end at {plan.name}"
    if failure.kind == "empty" and failure.rows is not None:
        inner = explain_empty(labels, failure.rows, plans[failure.index].name, span, "dead end", declarations)
        return PrscError(f"{head}: its region was empty ({inner.message.split(': ', 1)[-1]})", span, inner.notes)
    if failure.kind == "blocked":
        notes = tuple((f"blocked by {q.name}", plans[q.index].span) for q in failure.blockers)
        exclusions = plans[failure.index].exclusions
        notes += tuple((f"excluded by {labels[r.label_id].text}", r.span) for r in exclusions)
        why = "every position collides or is excluded" if exclusions else "every position collides"
        return PrscError(f"{head}: no free position ({why})", span, notes)
    if failure.kind == "require" and failure.label >= 0:
        lab = labels[failure.label]
        return PrscError(f"{head}: a require never held", span, ((f"this require: {lab.text}", lab.span),))
    return PrscError(head, span)
