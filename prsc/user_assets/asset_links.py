"""Links of the user's articulated assets (docs/assets.md, "Links"): the chain of bodies from
the world to a link, as numbers read once from the file (prsc/geometry/kinematics.py poses
it), and the link's collision geometry as boxes in its own frame. `X.links["NAME"]` carries one
(prsc/ir/asset_models.py) and the constraint stage places it at a scene's joint values.

Foundation module: imported by every layer, it imports mujoco only inside functions.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Sequence

import numpy as np

from prsc.user_assets.asset_files import JOINT_KINDS, ArticulatedAsset, asset_spec
from prsc.errors import PrscError, Span


@dataclass(frozen=True)
class JointAxis:
    """One hinge or slide joint of a body, in the body's frame."""

    name: str
    kind: str  # "revolute" or "prismatic"
    axis: tuple[float, float, float]  # unit
    anchor: tuple[float, float, float]  # a point on a hinge's axis


@dataclass(frozen=True)
class BodyStep:
    """A body's frame in its parent's (then moved by its joints, in order)."""

    position: tuple[float, float, float]
    quaternion: tuple[float, float, float, float]  # w x y z
    joints: tuple[JointAxis, ...]


@dataclass(frozen=True)
class AssetLink:
    """Link (body) `name` of an asset: the chain of bodies from the world to it, and its
    collision geometry as boxes in its own frame (lengths in m)."""

    name: str
    chain: tuple[BodyStep, ...]  # the root body first, this link last
    root_position: tuple[float, float, float]  # the root body's origin in the file's world
    boxes: tuple[tuple[tuple[float, float, float], tuple[float, float, float]], ...]  # (low, high) each
    meshes: int = 0  # how many of those boxes bound a collision mesh (MuJoCo collides one as its convex hull)


def asset_link(asset: ArticulatedAsset, name: str, folders: Sequence[str] = ()) -> AssetLink:
    """Link `name` of `asset` (a PrscError naming the links when there is none of that name)."""
    if name not in asset.links:
        from difflib import get_close_matches

        close = get_close_matches(name, asset.links, n=1)
        hint = f"; did you mean '{close[0]}'?" if close else ""
        raise PrscError(f"{Path(asset.source).name} has no link {name!r} (links: {', '.join(asset.links)}){hint}")
    return _asset_link(asset.source, asset.digest, tuple(folders), name)


@lru_cache(maxsize=256)
def _asset_link(source: str, digest: str, folders: tuple[str, ...], name: str) -> AssetLink:
    import mujoco

    model = asset_spec(Path(source), folders).compile()
    body = model.body(name).id
    chain, b = [], body
    while b != 0:
        joints = tuple(
            JointAxis(model.joint(j).name, JOINT_KINDS[int(model.jnt_type[j])],
                      tuple(float(v) for v in model.jnt_axis[j]), tuple(float(v) for v in model.jnt_pos[j]))
            for j in range(model.body_jntadr[b], model.body_jntadr[b] + model.body_jntnum[b]))
        chain.append(BodyStep(tuple(float(v) for v in model.body_pos[b]), tuple(float(v) for v in model.body_quat[b]),
                              joints))
        b = int(model.body_parentid[b])
    root = int(model.body_rootid[body])
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    boxes, meshes = [], 0
    for g in range(model.ngeom):
        if model.geom_bodyid[g] != body or not (model.geom_contype[g] or model.geom_conaffinity[g]):
            continue
        meshes += int(model.geom_type[g]) == int(mujoco.mjtGeom.mjGEOM_MESH)
        centre, half = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
        # The geom's box in the body frame (exact for boxes set along the body's axes).
        turn = np.zeros(9)
        mujoco.mju_quat2Mat(turn, model.geom_quat[g])
        local = (centre + corners * half) @ turn.reshape(3, 3).T + model.geom_pos[g]
        boxes.append((tuple(float(v) for v in local.min(axis=0)), tuple(float(v) for v in local.max(axis=0))))
    return AssetLink(name, tuple(reversed(chain)), tuple(float(v) for v in model.body_pos[root]), tuple(boxes), meshes)


def link_target_error(label: str, has_support: bool, hollow: bool, inside: bool, completely: bool,
                      span: Span | None, meshes: int = 0) -> None:
    """The error for `on`/`in` a link that has no support surface or is not hollow (none if it fits);
    `meshes`: how many of the link's collision geoms are meshes (each collides as its convex hull)."""
    word = ("completely " if completely else "") + ("in" if inside else "on")
    if inside and not hollow:
        why = (f" ({meshes} of its collision geoms {'is a mesh' if meshes == 1 else 'are meshes'}: MuJoCo collides "
               "a mesh as its convex hull, so a drawer or bin modelled as one mesh has no inside; give its floor "
               "and walls as collision geoms of their own, boxes or convex meshes)") if meshes else ""
        raise PrscError(f"`{word} {label}` needs a hollow link (a floor walled on four sides), and {label} is "
                        f"none{why}: to rest on it write `{'completely on' if completely else 'on'} {label}`", span)
    if not inside and not has_support:
        raise PrscError(f"`{word} {label}`: the link has no upward face with free space above it", span)


def check_link_target(label: str, link: AssetLink, inside: bool, completely: bool, span: Span | None) -> None:
    """The error for `on`/`in` link `link` (written `label`) when its geometry has no such surface: the
    same before any scene (its boxes are in its own frame, whatever its pose) for a placement and a task."""
    from prsc.geometry.link_surfaces import link_surfaces

    surfaces = link_surfaces(link.boxes)
    link_target_error(label, surfaces.support is not None, surfaces.interior is not None, inside, completely, span,
                      link.meshes)
