"""Where an arm lives in a MuJoCo model (docs/assets.md): its joints' addresses and limits, its
tool frame, its base, and which of its bodies may not touch: what the one IK
(prsc/user_assets/arm_ik.py) solves for and what a pose must keep to count.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

BELOW_BASE = 0.02  # m a link's origin may sink below the base's: UR arms' elbow-down answers went 0.2 m into the table
LIMIT_MARGIN = 0.02  # rad or m kept from every joint limit: a simulated servo held against its
# limit stops short of it (the limit constraint is soft), so a pose at a limit would miss.
# m two of the arm's links that are not neighbours may overlap before a pose counts as putting one
# into the other: collision meshes two links apart overlap by a few mm in ordinary poses. Top-down
# answers beside the base put the hand 5.5 cm into pybullet's Franka's base and the wrist 8 cm
# into the xArm6's (3 of 51 and 2 of 74 reached random points, 2026-11-27).
SELF_PENETRATION = 0.005
NOT_ARM = -2  # the segment of a body the arm does not carry


@dataclass(frozen=True)
class ArmFrames:
    """Where an arm lives in a model: its joints' qpos and dof addresses and its tool."""

    qpos: np.ndarray  # qpos address of each arm joint (hinge or slide), in order
    dofs: np.ndarray  # dof address of each
    lower: np.ndarray  # joint limits less LIMIT_MARGIN (-inf/inf when unlimited)
    upper: np.ndarray
    tool: int  # site id or body id
    tool_is_site: bool
    bodies: tuple[int, ...] = ()  # the bodies the joints move (each joint's body)
    base: int = 0  # the body the first joint's body hangs from: the arm's base
    # Per body of the model: the index of the joint body that carries it (in `bodies` order, first
    # seen), -1 for the base, NOT_ARM for the rest; and per segment the segment it hangs from.
    segments: tuple[int, ...] = ()
    segment_parents: tuple[int, ...] = ()

    @staticmethod
    def of(model, joints: list[str], tool: str) -> "ArmFrames":
        """The frames of joints `joints` and tool `tool` (a site, else a body) of `model`."""
        ids = [model.joint(name).id for name in joints]
        limited = model.jnt_limited[ids].astype(bool)
        try:
            tool_id, is_site = model.site(tool).id, True
        except KeyError:
            tool_id, is_site = model.body(tool).id, False
        low, high = model.jnt_range[ids, 0], model.jnt_range[ids, 1]
        # A range narrower than both margins (gym-aloha's vx300s has one) is held at its middle.
        middle = (low + high) / 2
        base = int(model.body_parentid[model.jnt_bodyid[ids[0]]])
        joint_bodies = list(dict.fromkeys(int(model.jnt_bodyid[j]) for j in ids))
        segments = [NOT_ARM] * model.nbody
        segments[base] = -1
        for body in range(1, model.nbody):  # a parent comes before its children
            if body in joint_bodies:
                segments[body] = joint_bodies.index(body)
            elif segments[int(model.body_parentid[body])] >= 0:
                segments[body] = segments[int(model.body_parentid[body])]
        return ArmFrames(
            qpos=model.jnt_qposadr[ids].copy(), dofs=model.jnt_dofadr[ids].copy(),
            lower=np.where(limited, np.minimum(low + LIMIT_MARGIN, middle), -np.inf),
            upper=np.where(limited, np.maximum(high - LIMIT_MARGIN, middle), np.inf),
            tool=tool_id, tool_is_site=is_site,
            bodies=tuple(int(model.jnt_bodyid[j]) for j in ids), base=base, segments=tuple(segments),
            segment_parents=tuple(segments[int(model.body_parentid[body])] for body in joint_bodies),
        )

    def above_base(self, data) -> bool:
        """Whether every body the joints move has its origin above the base's, less BELOW_BASE
        (after kinematics): an arm standing on a table keeps its links out of the table."""
        floor = data.xpos[self.base, 2] - BELOW_BASE
        return bool(all(data.xpos[body, 2] >= floor for body in self.bodies))

    def self_collides(self, model, data) -> bool:
        """Whether two of the arm's links that are not neighbours (nor the base and its first link)
        overlap by more than SELF_PENETRATION (after kinematics; writes `data`'s contacts)."""
        import mujoco

        mujoco.mj_collision(model, data)
        contact = data.contact
        for k in np.flatnonzero(contact.dist[:data.ncon] < -SELF_PENETRATION):
            a, b = (self.segments[model.geom_bodyid[contact.geom[k, g]]] for g in (0, 1))
            if NOT_ARM not in (a, b) and a != b and (a < 0 or self.segment_parents[a] != b) \
                    and (b < 0 or self.segment_parents[b] != a):
                return True
        return False

    def fits(self, model, data) -> bool:
        """Whether the pose in `data` keeps the arm above its base and out of itself (after kinematics)."""
        return self.above_base(data) and not self.self_collides(model, data)

    def heading(self, data, root: np.ndarray) -> float:
        """The azimuth of the tool about the point `root` (the arm's root) in `data` (after kinematics)."""
        tool = self.tool_pose(data)[0] - root
        return math.atan2(tool[1], tool[0])

    def tool_pose(self, data) -> tuple[np.ndarray, np.ndarray]:
        """The tool's world position and rotation matrix in `data` (after kinematics)."""
        if self.tool_is_site:
            return data.site_xpos[self.tool].copy(), data.site_xmat[self.tool].reshape(3, 3).copy()
        return data.xpos[self.tool].copy(), data.xmat[self.tool].reshape(3, 3).copy()
