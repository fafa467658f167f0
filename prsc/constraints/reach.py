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

from prsc.asset_files import describe_asset, names_asset_file
from prsc.constraints.values import ObjectValue
from prsc.ir.models import model_of
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



def _rows_file_arm(robot: ObjectValue, path: str, label: int, span: Span | None) -> Polytope:
    """`reachable by` an arm from a file: its cell in its root frame, moved to the root's pose."""
    from prsc.constraints.arm_reach import arm_reach_cell

    asset = describe_asset(path)
    if not asset.has_joints:
        raise PrscError(f"'reachable by' needs a robot: {robot.name}'s model {asset.name!r} has no joints", span)
    try:
        cell = arm_reach_cell(asset)
    except ValueError as error:
        raise PrscError(f"'reachable by' {robot.name}: {error}", span) from None
    if robot.position is None or robot.rotation is None or robot.dims is None:
        raise PrscError(f"{robot.name} is not placed yet here", span)
    rot = robot.rotation
    root = robot.position + rot @ np.array(asset.root_offset)
    a = cell.a @ rot.T
    return Polytope(a, cell.b + a @ root, np.zeros((0, 3)), np.zeros(0), np.full(len(a), label), np.zeros(0, np.int64))


def rows_reachable(robot: object, label: int, span: Span | None) -> Polytope:
    """`reachable by R`: p in R's reachable cell, moved to R's pose (base = centre - height/2 along R's z)."""
    if not isinstance(robot, ObjectValue):
        raise PrscError("'reachable by' needs a robot object", span)
    model = model_of(robot.props, robot.class_name)
    if names_asset_file(model):
        return _rows_file_arm(robot, str(model), label, span)
    cell = reach_cell(model) if isinstance(model, str) else None
    if cell is None:
        raise PrscError(f"'reachable by' needs a robot (the Panda, or an arm from a URDF or MJCF file: "
                        f"docs/assets.md); {robot.name}'s model is {model!r}", span)
    if robot.position is None or robot.rotation is None or robot.dims is None:
        raise PrscError(f"{robot.name} is not placed yet here", span)
    a_local, b_local = cell
    rot = robot.rotation
    base = robot.position - rot[:, 2] * (robot.dims[2] * 0.5)
    # a . R^T (p - base) <= b  <=>  (a R^T) . p <= b + (a R^T) . base
    a = a_local @ rot.T
    return Polytope(a, b_local + a @ base, np.zeros((0, 3)), np.zeros(0), np.full(len(a), label), np.zeros(0, np.int64))
