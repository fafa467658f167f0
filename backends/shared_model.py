"""One MuJoCo model per spec, and new scenes written into it without recompiling
(docs/learning.md): what an RL reset needs.

`SharedModel(scene, model, store, folder)` wraps the compiled MJCF of one scene (the
library's `scenario.model()`, prsc/scenario.py); every scene of the same spec has the same
bodies, joints, geoms and actuators, so `apply` writes another scene's numbers into that
model and its data:

- poses: free bodies' `qpos` (and their `qpos0`, `body_pos`/`body_quat`, as a fresh model
  has them), fixed bodies' `body_pos`/`body_quat` (cameras, robots, furniture);
- primitive geoms: `geom_size`, `geom_pos`/`geom_quat`, and what MuJoCo's compiler derives
  from them (`geom_rbound`, `geom_aabb`); bodies' mass, centre of mass and inertia, computed
  by the same code as the MJCF writer (prsc.backends.bodies); `mj_setConst` then redoes
  the constants that depend on them;
- colours, camera field of view, robots' joint values and the `home` keyframe (qpos, ctrl);
- then `mj_resetDataKeyframe(home)` and `mj_forward`.

A scene the shared model cannot express is an error naming the object and why: another
set of objects, another shape, model or part layout, a mesh whose size changes (a mesh's
scale is baked into its vertices), another image (`with texture Options(...)`: the image is
compiled into the model's texture data), or a robot from another file.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from prsc.backends.bodies import Body, resolve_bodies
from prsc.backends.mjcf import RobotFragment, _geom_rgba, _geom_size, robot_fragment
from prsc.backends.scene import parse_scene, scene_position, unit_quaternion
from prsc.backends.store import AssetStore
from prsc.errors import PrscError


@dataclass(frozen=True)
class _Layout:
    """What must be equal between two scenes for one model to hold both."""

    objects: tuple[tuple[Any, ...], ...]  # per object: name, fixed, robot key, camera, parts' (name, shape, mesh, ..., texture)

    @staticmethod
    def of(bodies: tuple[Body, ...]) -> "_Layout":
        """The layout of resolved bodies."""
        return _Layout(tuple(
            (b.name, b.fixed, b.robot.key if b.robot else None, b.camera is not None,
             tuple((p.name, p.shape, p.mesh, p.collides, p.visible, p.texture) for p in b.parts))
            for b in bodies
        ))


def _difference(old: _Layout, new: _Layout) -> str:
    """Why `new` does not fit a model built for `old`, naming the object."""
    names_old, names_new = [o[0] for o in old.objects], [o[0] for o in new.objects]
    if names_old != names_new:
        return (f"its objects are {', '.join(names_new)}, the model's {', '.join(names_old)} "
                "(another number of objects or other names)")
    for before, after in zip(old.objects, new.objects):
        if before == after:
            continue
        name = after[0]
        if before[1] != after[1]:
            return f"object {name!r} is {'fixed' if after[1] else 'free'} here, {'fixed' if before[1] else 'free'} in the model"
        if before[2] != after[2]:
            return f"object {name!r} is another robot ({after[2]}) than in the model ({before[2]})"
        shapes_before = [p[:2] for p in before[4]]
        shapes_after = [p[:2] for p in after[4]]
        if shapes_before != shapes_after:
            return f"object {name!r} has other parts or shapes ({shapes_after}) than in the model ({shapes_before})"
        images_before = [p[5] for p in before[4]]
        images_after = [p[5] for p in after[4]]
        if images_before != images_after:
            # An image is compiled into the model's texture data, like a mesh's vertices.
            return (f"object {name!r} shows another image ({_names(images_after)}) than in the model "
                    f"({_names(images_before)}); a shared model cannot change a texture: compile each scene")
        return f"object {name!r}'s parts differ from the model's ({after[4]} vs {before[4]})"
    return "its layout differs"  # pragma: no cover - equal layouts are not compared


def _names(images: list[str | None]) -> str:
    """The file names of parts' images, for an error."""
    return ", ".join(Path(i).name if i else "none" for i in images)


def _signature(raw: Mapping[str, Any]) -> dict[str, Any]:
    """An object of scene JSON without its pose: what decides its sizes, masses and joints."""
    return {k: v for k, v in raw.items() if k not in ("position", "quaternion")}


def _bounds(shape: str, size: tuple[float, ...]) -> tuple[float, np.ndarray]:
    """MuJoCo's bounding sphere radius and axis-aligned half sizes of a primitive geom."""
    if shape == "box":
        half = np.array(size[:3])
        return float(np.linalg.norm(half)), half
    if shape == "cylinder":
        radius, half_height = size[0], size[1]
        return float(np.hypot(radius, half_height)), np.array([radius, radius, half_height])
    radius = size[0]
    return float(radius), np.array([radius, radius, radius])


class SharedModel:
    """A compiled MuJoCo model of a spec's scenes, and how to write a scene into it."""

    def __init__(self, scene: Mapping[str, Any], model, store: AssetStore, folder: Path) -> None:
        self.model = model
        self.store = store
        self.folder = folder
        bodies = resolve_bodies(parse_scene(scene), store)
        self.layout = _Layout.of(bodies)
        # A mesh's scale is baked into the compiled vertices: the model's must stay.
        self._mesh_scales = {(b.name, p.name): np.array(p.size) for b in bodies for p in b.parts if p.shape == "mesh"}
        self._signatures: list[dict[str, Any]] | None = None  # of the scene applied last: all but poses
        self._bodies = bodies
        self._body_ids = np.array([model.body(b.name).id for b in bodies], dtype=int)
        self._free = np.array([not b.fixed for b in bodies], dtype=bool)
        # Each free body's 7 qpos entries (position, quaternion), in scene order.
        self._free_qpos = np.array([model.jnt_qposadr[model.joint(b.name).id] + k
                                    for b in bodies if not b.fixed for k in range(7)], dtype=int)
        self._home = model.key("home").id if model.nkey else None
        self._robot_qpos = np.zeros(model.nq)
        self._robot_ctrl = np.zeros(model.nu)

    def apply(self, scene_json: Mapping[str, Any], data) -> None:
        """Write a scene into the model and `data`, then reset `data` to its `home` key and forward."""
        import mujoco

        model = self.model
        if not self._only_poses_changed(scene_json):
            self._apply_whole(scene_json)
        poses = np.array([scene_position(raw.get("position"), f"scene JSON: object {body.name!r}.position")
                          + unit_quaternion(raw.get("quaternion"), f"scene JSON: object {body.name!r}.quaternion")
                          for body, raw in zip(self._bodies, scene_json["objects"])], dtype=float).reshape(-1, 7)
        model.body_pos[self._body_ids] = poses[:, :3]
        model.body_quat[self._body_ids] = poses[:, 3:]
        free = poses[self._free]
        model.qpos0[self._free_qpos] = free.ravel()
        home = self._home
        if home is not None:
            # The home key holds free bodies where they are and robots at their joints.
            key = model.key_qpos[home]
            key[:] = self._robot_qpos
            key[self._free_qpos] = free.ravel()
            if model.nu:
                model.key_ctrl[home] = self._robot_ctrl
        mujoco.mj_setConst(model, data)
        if home is not None:
            mujoco.mj_resetDataKeyframe(model, data, home)
        else:
            mujoco.mj_resetData(model, data)
        mujoco.mj_forward(model, data)

    def _only_poses_changed(self, scene_json: Mapping[str, Any]) -> bool:
        """Whether every object but its pose is as in the scene applied last (a cheap reset)."""
        objects = scene_json.get("objects") if isinstance(scene_json, Mapping) else None
        return (self._signatures is not None and isinstance(objects, list) and len(objects) == len(self._signatures)
                and all(isinstance(o, Mapping) and _signature(o) == s for o, s in zip(objects, self._signatures)))

    def _apply_whole(self, scene_json: Mapping[str, Any]) -> None:
        """Validate the scene and write everything but the poses: sizes, masses, colours, joints."""
        scene = parse_scene(scene_json)
        bodies = resolve_bodies(scene, self.store)
        layout = _Layout.of(bodies)
        if layout != self.layout:
            raise PrscError(f"scene {scene.index} does not fit this spec's shared MuJoCo model: "
                            f"{_difference(self.layout, layout)}")
        robot_qpos = np.zeros(self.model.nq)
        ctrl: list[float] = []
        for body in bodies:
            self._write_body(body)
            if body.robot is not None:
                fragment = robot_fragment(body.robot, f"{body.name}/", self.store, self.folder)
                joints, servo = self._robot_home(fragment, body)
                for name, value in zip(fragment.joints, joints):
                    robot_qpos[self.model.jnt_qposadr[self.model.joint(f"{body.name}/{name}").id]] = value
                ctrl += servo
        self._bodies = bodies
        self._robot_qpos = robot_qpos
        self._robot_ctrl = np.array(ctrl)
        self._signatures = [_signature(o) for o in scene_json["objects"]]

    @staticmethod
    def _robot_home(fragment: RobotFragment, body: Body) -> tuple[list[float], list[float]]:
        """The robot's qpos and ctrl in the home key, as numbers."""
        assert body.robot is not None
        qpos, ctrl = fragment.home(body.robot, dict(body.obj.joints))
        return [float(v) for v in qpos], [float(v) for v in ctrl]

    def _write_body(self, body: Body) -> None:
        """Mass properties, geoms, colours and camera of one object (its pose: `apply`)."""
        model = self.model
        obj = body.obj
        b = model.body(obj.name).id
        inertial = body.inertial
        model.body_mass[b] = inertial.mass
        model.body_ipos[b] = inertial.com
        model.body_iquat[b] = inertial.principal
        model.body_inertia[b] = inertial.diagonal
        for part in body.parts:
            g = model.geom(f"{obj.name}/{part.name}").id
            model.geom_pos[g] = part.position
            model.geom_quat[g] = part.quaternion
            model.geom_rgba[g] = _geom_rgba(obj, part)
            if part.shape == "mesh":
                self._check_mesh_scale(obj.name, part.name, np.array(part.size))
                continue
            size = _geom_size(part)
            model.geom_size[g] = size
            rbound, half = _bounds(part.shape, size)
            model.geom_rbound[g] = rbound
            model.geom_aabb[g] = np.concatenate([np.zeros(3), half])
        if body.camera is not None:
            model.cam_fovy[model.camera(obj.name).id] = body.camera.fovy

    def _check_mesh_scale(self, name: str, part: str, scale: np.ndarray) -> None:
        """A mesh's scale is baked into its compiled vertices: it must not change."""
        first = self._mesh_scales[(name, part)]
        if not np.allclose(first, scale, rtol=0, atol=1e-12):
            raise PrscError(f"object {name!r} is a mesh whose size changes between scenes ({first.tolist()} in the "
                            f"model, {scale.tolist()} here); a shared model cannot rescale a mesh: compile each scene")
