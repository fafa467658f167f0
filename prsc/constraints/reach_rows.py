"""`reachable by R`: the robot's top-down reach as exact rows: an outer convex cell (the
rule `reachable`) minus a convex hole about the base and a wedge-shaped gap where the base
cannot turn (the two excluded cells `unreachable`).

For the Panda, prsc/constraints/panda_reach.json holds them in the arm base's frame
(origin at the bottom centre of the Robot box, +y ahead, +z up), inside the set of points
the tool centre reaches with the gripper pointing down (the handover's grasp). It is
computed once from the arm's kinematics by `python -m prsc.commands.reach` and checked
against the IK by tests/constraints/test_reach.py. An arm from a file gets the same from
its own kinematics (arm_reach.py), in its object's axes too (+y ahead). docs/sampling.md says how much of the reach they keep.
"""

from __future__ import annotations

import functools
import json
from dataclasses import replace
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from prsc.user_assets.asset_files import ROOT_OFFSET, describe_asset, names_asset_file
from prsc.constraints.values import ObjectValue
from prsc.ir.models import model_of
from prsc.errors import PrscError, Span
from prsc.geometry.polytope import Polytope
from prsc.constraints.reach_ring import ReachRing, ring_from_json

DATA = Path(__file__).resolve().parent


@functools.lru_cache(maxsize=None)
def reach_ring(model: str) -> ReachRing | None:
    """The model's reach rows in its base frame, or None when prsc has no data for it."""
    path = reach_file(model)
    if not path.is_file():
        return None
    return ring_from_json(json.loads(path.read_text(encoding="utf-8"))["ring"])


def reach_file(model: str) -> Path:
    """Where a robot model's reachable-set data lives."""
    return DATA / f"{model}_reach.json"


def local_ring(props: Mapping[str, Any], class_name: str, name: str,
               span: Span | None) -> tuple[ReachRing, np.ndarray | None]:
    """A robot's reach rows in its base frame, and its root in its box from the box centre
    (None: the base is the box's bottom centre, the built-in Panda's), from its properties."""
    model = model_of(props, class_name)
    if names_asset_file(model):
        from prsc.constraints.arm_reach import arm_reach

        asset = describe_asset(str(model))
        if not asset.has_joints:
            raise PrscError(f"'reachable by' needs a robot: {name}'s model {asset.name!r} has no joints", span)
        tool = props.get("tcp")
        if isinstance(tool, str) and tool != asset.tcp:
            asset = replace(asset, tcp=tool)  # the spec's tool frame (`with tcp "link"`): its own reach
        try:
            ring = arm_reach(asset).ring
        except ValueError as error:
            # The usual cause is the tool frame: a link whose +z does not point out of the hand.
            others = ", ".join(repr(link) for link in (*asset.sites, *asset.links[-3:]) if link != asset.tcp)
            raise PrscError(f"'reachable by' {name}: {error}, with the tool frame {asset.tcp!r} pointing "
                            f"its +z down; name the tool with `with tcp \"NAME\"` (a link or site of the file: "
                            f"{others})", span) from None
        return ring, np.array(props.get(ROOT_OFFSET, asset.root_offset), dtype=float)
    found = reach_ring(model) if isinstance(model, str) else None
    if found is None:
        raise PrscError(f"'reachable by' needs a robot (the Panda, or an arm from a URDF or MJCF file: "
                        f"docs/assets.md); {name}'s model is {model!r}", span)
    return found, None


def _placed_ring(robot: object, span: Span | None) -> tuple[ReachRing, np.ndarray, np.ndarray]:
    """R's reach rows in its base frame, the base's position and R's rotation.

    The base is the root body of an arm from a file, else the bottom centre of R's box."""
    if not isinstance(robot, ObjectValue):
        raise PrscError("'reachable by' needs a robot object", span)
    ring, offset = local_ring(robot.props, robot.class_name, robot.name, span)
    if robot.position is None or robot.rotation is None or robot.dims is None:
        raise PrscError(f"{robot.name} is not placed yet here", span)
    rot = robot.rotation
    base = robot.position + rot @ offset if offset is not None else robot.position - rot[:, 2] * (robot.dims[2] * 0.5)
    return ring, base, rot


def _moved(a_local: np.ndarray, b_local: np.ndarray, base: np.ndarray, rot: np.ndarray, label: int) -> Polytope:
    # a . R^T (p - base) <= b  <=>  (a R^T) . p <= b + (a R^T) . base
    a = a_local @ rot.T
    return Polytope(a, b_local + a @ base, np.zeros((0, 3)), np.zeros(0), np.full(len(a), label), np.zeros(0, np.int64))


def rows_reachable(robot: object, label: int, span: Span | None) -> Polytope:
    """`reachable by R`: p in the outer cell of R's reach, moved to R's pose."""
    ring, base, rot = _placed_ring(robot, span)
    return _moved(ring.a, ring.b, base, rot, label)


def rows_unreachable(robot: object, part: int, label: int, span: Span | None) -> Polytope:
    """`reachable by R`'s excluded cell `part` (0: the hole about R's base, 1: the gap), moved to R's pose."""
    ring, base, rot = _placed_ring(robot, span)
    return _moved(*ring.excluded()[part], base, rot, label)
