"""IR -> polytope constraint IR (labelled half-space rows per object)."""

from __future__ import annotations

from prsc.constraints.lower import lower_program
from prsc.constraints.polytope_ir import ConstraintProgram, ObjectPlan, RowLabel

__all__ = ["ConstraintProgram", "ObjectPlan", "RowLabel", "lower_program"]
