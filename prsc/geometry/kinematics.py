"""Forward kinematics of a chain of bodies (pure math): where a link of an articulated asset
is at given joint values. The chain is data read once from the asset's file
(prsc/user_assets/asset_links.py); the constraint stage places `X.links["NAME"]` with it."""

from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from prsc.geometry.rotations import quat_to_matrix


def axis_angle(axis: ArrayLike, angle: float) -> NDArray[np.float64]:
    """The rotation by `angle` (rad) about the unit `axis` (Rodrigues)."""
    x, y, z = (float(v) for v in axis)
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)


def chain_pose(chain: Sequence[Any], joints: Mapping[str, float]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(position, rotation) of the last body of `chain` in the frame of the first one's parent.

    Each step has `position`, `quaternion` (w x y z: its frame in its parent's) and `joints`,
    each with `name`, `kind` ("revolute" or "prismatic"), a unit `axis` and an `anchor` on a
    hinge's axis, in the body's frame; a joint missing from `joints` stands at 0."""
    position, rotation = np.zeros(3), np.eye(3)
    for step in chain:
        position = position + rotation @ np.asarray(step.position, dtype=float)
        rotation = rotation @ quat_to_matrix(step.quaternion)
        for joint in step.joints:
            value = float(joints.get(joint.name, 0.0))
            axis = np.asarray(joint.axis, dtype=float)
            if joint.kind == "prismatic":
                position = position + rotation @ (axis * value)
            else:  # turn about the axis through the anchor
                anchor = np.asarray(joint.anchor, dtype=float)
                turn = axis_angle(axis, value)
                position = position + rotation @ (anchor - turn @ anchor)
                rotation = rotation @ turn
    return position, rotation
