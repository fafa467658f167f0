"""`reachable by R`: the robot model's top-down reachable set as rows, read from shipped data.

prsc/constraints/<model>_reach.json holds, in the arm base's frame (origin at the bottom
centre of the Robot box, +y ahead, +z up), convex cells inside the set of points the
tool centre reaches with the gripper pointing down (the handover's grasp). It is
computed once from the arm's kinematics by `python -m prsc.commands.reach` (IK over a
grid) and checked against the IK by tests/constraints/test_reach.py; docs/sampling.md
says how much of the reachable set it keeps.
"""

from __future__ import annotations

import functools
import json
from pathlib import Path

import numpy as np

from prsc.constraints.values import ObjectValue
from prsc.errors import PrscError, Span
from prsc.geometry.polytope import Polytope

DATA = Path(__file__).resolve().parent


@functools.lru_cache(maxsize=None)
def reach_cell(model: str) -> tuple[np.ndarray, np.ndarray] | None:
    """(A, b) of the model's convex cell in its base frame, or None when prsc has no data for it."""
    path = reach_file(model)
    if not path.is_file():
        return None
    data = json.loads(path.read_text(encoding="utf-8"))
    cell = data["cell"]
    return np.array(cell["A"], dtype=float), np.array(cell["b"], dtype=float)


def reach_file(model: str) -> Path:
    """Where a robot model's reachable-set data lives."""
    return DATA / f"{model}_reach.json"


def known_models() -> list[str]:
    """Robot models with reachable-set data."""
    return sorted(p.name[: -len("_reach.json")] for p in DATA.glob("*_reach.json"))


def rows_reachable(robot: object, label: int, span: Span | None) -> Polytope:
    """`reachable by R`: p in R's reachable cell, moved to R's pose (base = centre - height/2 along R's z)."""
    if not isinstance(robot, ObjectValue):
        raise PrscError("'reachable by' needs a robot object", span)
    model = robot.props.get("model")
    cell = reach_cell(model) if isinstance(model, str) else None
    if cell is None:
        models = ", ".join(known_models()) or "none"
        raise PrscError(f"'reachable by' has no reachable-set data for {robot.name}'s model {model!r} (known: {models})", span)
    if robot.position is None or robot.rotation is None or robot.dims is None:
        raise PrscError(f"{robot.name} is not placed yet here", span)
    a_local, b_local = cell
    rot = robot.rotation
    base = robot.position - rot[:, 2] * (robot.dims[2] * 0.5)
    # a . R^T (p - base) <= b  <=>  (a R^T) . p <= b + (a R^T) . base
    a = a_local @ rot.T
    return Polytope(a, b_local + a @ base, np.zeros((0, 3)), np.zeros(0), np.full(len(a), label), np.zeros(0, np.int64))
