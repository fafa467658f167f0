"""`reachable by R`: the robot's top-down reach as exact rows: an outer convex cell (the
rule `reachable`) minus a convex hole about the base and a wedge-shaped gap where the base
cannot turn (the two excluded cells `unreachable`).

Every robot is an arm read from a file (the user's URDF or MJCF, or a library arm: its file
and what the library adds), and its reach is built from its own kinematics by one builder
(arm_reach.py), about its root body in its object's axes (+y ahead, +z up). docs/assets.md
says how much of the true reach it keeps.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Mapping

import numpy as np

from prsc.user_assets.asset_files import ROOT_OFFSET, model_asset, names_asset
from prsc.constraints.values import ObjectValue
from prsc.ir.models import model_of
from prsc.errors import PrscError, Span
from prsc.geometry.polytope import Polytope
from prsc.constraints.reach_ring import ReachRing


def local_ring(props: Mapping[str, Any], class_name: str, name: str, span: Span | None) -> tuple[ReachRing, np.ndarray]:
    """A robot's reach rows about its root, in its object's axes, and its root in its box from
    the box centre, from its properties."""
    from prsc.constraints.arm_reach import arm_reach

    model = model_of(props, class_name)
    if not names_asset(model):
        raise PrscError(f"'reachable by' needs a robot (an arm from a URDF or MJCF file, or the library's: "
                        f"docs/assets.md); {name}'s model is {model!r}", span)
    asset = model_asset(str(model))
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


def _placed_ring(robot: object, span: Span | None) -> tuple[ReachRing, np.ndarray, np.ndarray]:
    """R's reach rows about its root body, the root's position and R's rotation."""
    if not isinstance(robot, ObjectValue):
        raise PrscError("'reachable by' needs a robot object", span)
    ring, offset = local_ring(robot.props, robot.class_name, robot.name, span)
    if robot.position is None or robot.rotation is None or robot.dims is None:
        raise PrscError(f"{robot.name} is not placed yet here", span)
    rot = robot.rotation
    return ring, robot.position + rot @ offset, rot


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
