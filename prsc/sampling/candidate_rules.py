"""What the candidate sampler (candidates.py) computes per candidate besides values: a box's
support function over many candidates, and the fixed regions a rule may read."""

from __future__ import annotations

from typing import Callable

import numpy as np

from prsc.constraints.context import SceneContext
from prsc.constraints.polytope_ir import Rule
from prsc.constraints.values import RegionValue
from prsc.geometry.polytope import Polytope
from prsc.sampling.batch_values import Unbatchable
from prsc.sampling.candidate_values import CandidateState

Test = Callable[[CandidateState], np.ndarray]  # (n,) bool: the candidates that pass


def support(normals: np.ndarray, rotation: np.ndarray, half: np.ndarray) -> np.ndarray:
    """s(n) of each candidate's box along its own normals: normals (n, m, 3), rotation (n, 3, 3), half (n, 3) -> (n, m)."""
    return (np.abs(np.matmul(normals, rotation)) * half[:, None, :]).sum(axis=2)


def constant_value_of(rule: Rule) -> object:
    """A rule's first argument when it is the same in every scene (Unbatchable otherwise)."""
    try:
        return rule.values[0](SceneContext(None))  # type: ignore[arg-type]  # a constant reads no stream
    except Exception:  # noqa: BLE001 - any failure means the value is not a constant
        raise Unbatchable("a value that changes between scenes") from None


def constant_region(rule: Rule) -> Polytope:
    """The fixed region a workspace rule reads (Unbatchable unless it is the same in every scene)."""
    value = constant_value_of(rule)
    if not isinstance(value, RegionValue) or len(value.poly.d):
        raise Unbatchable("a workspace that is not a solid region")
    return value.poly
