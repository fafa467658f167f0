"""One MuJoCo model per spec, and new scenes written into it without recompiling
(docs/learning.md): what an RL reset needs.

`SharedModel(scene, spec, store, folder, images)` compiles the MJCF of one scene (the
library's `scenario.model()`, prsc/scenario.py) with every image the spec can draw loaded
once; every scene of the same spec has the same structure (backends/scene_structure.py:
bodies, joints, geoms, cameras, actuators, ground), so `apply` writes another scene's
numbers into that model and its data:

- poses: free bodies' `qpos` (and their `qpos0`, `qpos_spring`, `body_pos`/`body_quat`, as a fresh model
  has them), fixed bodies' `body_pos`/`body_quat` (cameras, robots, furniture);
- primitive geoms: `geom_size`, `geom_pos`/`geom_quat`, and what MuJoCo's compiler derives
  from them (`geom_rbound`, `geom_aabb`); bodies' mass, centre of mass and inertia, computed
  by the same code as the MJCF writer (prsc.backends.bodies); `mj_setConst` then redoes
  the constants that depend on them;
- each textured geom's material (`geom_matid`): the one showing the scene's image;
- colours, camera field of view, lights, robots' joint values and the `home` keyframe (qpos, ctrl);
- `stat.center`/`stat.extent` as the compiler derives them (cameras' clip planes scale with them);
- then `mj_resetDataKeyframe(home)` and `mj_forward`.

Only the objects whose JSON changed since the scene applied last are written again. An object
that is one primitive (backends/bodies.py `primitive_shape`: a box, cylinder or sphere with no
image, camera or container interior) and whose dimensions and mass alone changed is not parsed
or resolved: its new numbers are validated as the scene parser does, and its geom size, bounds,
mass and inertia are computed for all such objects at once by the formulas the MJCF writer uses
(`primitive_extents`, `primitive_geom_sizes`, `primitive_inertia`): every primitive's size and
mass is written that way, also in a whole scene. Any other change parses and resolves the object
again; an object whose image alone changed only switches material.

A scene the shared model cannot hold is an error naming what differs: another structure
(another set of objects, ground, shape, robot, camera resolution...), a mesh whose file or
size changes (a mesh's scale is baked into its vertices), or an image the model did not load.
"""

from __future__ import annotations

from dataclasses import replace
from itertools import chain
from pathlib import Path
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from prsc.backends.bodies import (Body, light_directions, primitive_extents, primitive_shape, resolve_body,
                                  resolve_bodies, texture_image)
from prsc.backends.inertia import primitive_inertia
from prsc.backends.mjcf import RobotFragment, geom_rgba, geom_size, primitive_geom_sizes, robot_fragment
from prsc.backends.scene import (Scene, object_dimensions, object_mass, parse_object, parse_scene, scene_position,
                                 unit_quaternion)
from prsc.backends.scene_structure import SceneStructure, difference, scene_structure
from prsc.backends.store import AssetStore
from prsc.errors import PrscError
from prsc.limits import MAX_MASS, MAX_SIZE, MIN_SIZE


def _is_mapping(value: Any) -> bool:
    """isinstance(value, Mapping), at a dict's cost where it is one (an ABC check costs 0.5 us, 30 per reset)."""
    return type(value) is dict or isinstance(value, Mapping)


def _signature(raw: Mapping[str, Any]) -> dict[str, Any]:
    """An object of scene JSON without its pose and image: what decides its sizes, masses and joints."""
    signature = dict(raw)
    signature.pop("position", None)
    signature.pop("quaternion", None)
    properties = raw.get("properties")
    if _is_mapping(properties) and "texture" in properties:
        signature["properties"] = {k: v for k, v in properties.items() if k != "texture"}
    return signature


SIZE_KEYS = ("dimensions", "mass")
"""What of a primitive object's JSON is written without parsing it (`_resize`)."""


def _sized_alike(signature: dict[str, Any], old: Mapping[str, Any]) -> bool:
    """Whether two objects' signatures differ in their dimensions and mass at most."""
    if signature.keys() != old.keys():
        return False
    probe = dict(signature)  # compared whole (in C), with the old dimensions and mass
    for key in SIZE_KEYS:
        if key in old:
            probe[key] = old[key]
    return probe == old


def _bounds(shape: str, sizes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo's bounding sphere radii and axis-aligned half sizes of primitive geoms of MuJoCo `sizes` (rows)."""
    if shape == "box":
        return np.sqrt(np.einsum("ij,ij->i", sizes, sizes)), sizes
    radius = sizes[:, 0]
    half = np.empty_like(sizes)
    half[:, 0], half[:, 1], half[:, 2] = radius, radius, sizes[:, 1] if shape == "cylinder" else radius
    return (np.hypot(radius, sizes[:, 1]) if shape == "cylinder" else radius.copy()), half


def _as_slice(ids: np.ndarray) -> slice | np.ndarray:
    """Consecutive ids as a slice (numpy writes through one at half the cost of an index array), else the ids."""
    if len(ids) and np.array_equal(ids, np.arange(ids[0], ids[0] + len(ids))):
        return slice(int(ids[0]), int(ids[0]) + len(ids))
    return ids


def _sizes_at_once(objects: list[Any], resized: Iterable[int], free: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The `resized` objects' dimensions (rows) and masses when every one is valid as the scene parser
    checks them (`object_dimensions`, `object_mass`), tested all at once; None when one may not be."""
    try:
        raws = [objects[k] for k in resized]
        dims, masses = [raw["dimensions"] for raw in raws], [raw["mass"] for raw in raws]
        exact = ({type(d) for d in dims} <= {list, tuple} and {type(v) for v in chain(masses, *dims)} <= {float, int})
        dimensions, mass = np.array(dims, dtype=float), np.array(masses, dtype=float)
    except (KeyError, TypeError, ValueError):
        return None
    if not exact or dimensions.shape != (len(raws), 3):
        return None
    # limits.size_problem and mass_problem, with NaN failing every comparison (a NaN is each reduction's value).
    fits = dimensions.min() >= MIN_SIZE and dimensions.max() <= MAX_SIZE and mass.min() >= 0.0 and mass.max() <= MAX_MASS
    if not fits or (mass.min() == 0.0 and (free[list(resized)] & (mass == 0.0)).any()):
        return None
    return dimensions, mass


def _image_name(raw: Mapping[str, Any]) -> Any:
    """The image an object of scene JSON names (`with texture`), or None."""
    properties = raw.get("properties")
    return properties.get("texture") if _is_mapping(properties) else None


def _images(scene: Scene, bodies: tuple[Body, ...], store: AssetStore,
            choices: Mapping[str, Sequence[str]]) -> tuple[str, ...]:
    """Every image (the store's copy) that the objects of the spec can show, once each."""
    paths: dict[str, None] = {}
    for body in bodies:
        obj = body.obj
        if "texture" not in obj.properties:
            continue
        names = choices.get(obj.label)
        if names is None:
            raise PrscError(f"object {obj.label!r}: its image (`with texture`) is not drawn from a list of file names, "
                            "so one model cannot load every image it may show: write `with texture "
                            "Options([...])`, or compile each scene", obj=obj.label)
        for name in names:
            paths.setdefault(texture_image(replace(obj, properties={**obj.properties, "texture": name}), scene, store))
    return tuple(paths)


class _Statistics:
    """`model.stat.center` and `extent` as MuJoCo's compiler sets them at `qpos0`: the box round the
    bodies, their centres of mass, joint anchors, sites and geoms' bounding spheres (a plane's:
    a tenth of its size, 0.01 when infinite, as measured on MuJoCo 4.0). Cameras and the free
    camera scale their clip planes by `extent`, so an image depends on them."""

    def __init__(self, model) -> None:
        import mujoco

        planes = (model.geom_rbound == 0) & (model.geom_type == int(mujoco.mjtGeom.mjGEOM_PLANE))
        finite = np.max(model.geom_size[:, :2], axis=1)
        plane_radius = np.where(finite > 0, 0.1 * finite, 0.01)
        # Which geoms count is structure (a sized primitive or a mesh has a radius; a plane its own).
        self.geoms = np.flatnonzero((model.geom_rbound > 0) | planes)
        self.planes = np.flatnonzero(planes[self.geoms])
        self.plane_radius = plane_radius[planes]

    def set(self, model, data) -> None:
        """Set them from `data`'s kinematics at `qpos0`."""
        radius = model.geom_rbound[self.geoms]
        radius[self.planes] = self.plane_radius
        centres = data.geom_xpos[self.geoms]
        points = np.concatenate((data.xpos[1:], data.xipos[1:], data.xanchor, data.site_xpos,
                                 centres - radius[:, None], centres + radius[:, None])).T.copy()
        low, high = points.min(axis=1), points.max(axis=1)  # along rows: 4x faster than down columns
        model.stat.center[:] = (low + high) / 2
        model.stat.extent = max(float(np.max(high - low)), 1e-5, 2 * model.stat.meansize)


class SharedModel:
    """A compiled MuJoCo model of a spec's scenes, and how to write a scene into it."""

    def __init__(self, scene_json: Mapping[str, Any], spec, store: AssetStore, folder: Path,
                 images: Mapping[str, Sequence[str]]) -> None:
        """Compile `spec` (the MjSpec of `scene_json`) with every image of `images` (object -> the
        file names its `texture` can draw) loaded once."""
        import mujoco

        self.store = store
        self.folder = folder
        scene = parse_scene(scene_json)
        bodies = resolve_bodies(scene, store)
        paths = _images(scene, bodies, store, images)
        for k, path in enumerate(paths):
            # As the MJCF writer shows an image on a primitive: a cube texture, its own colour space.
            name = f"prsc_image/{k}"
            spec.add_texture(name=name, type=mujoco.mjtTexture.mjTEXTURE_CUBE, file=path,
                             colorspace=mujoco.mjtColorSpace.mjCOLORSPACE_AUTO)
            spec.add_material(name=name).textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = name
        self.model = model = spec.compile()
        self._image_material = {path: model.material(f"prsc_image/{k}").id for k, path in enumerate(paths)}
        self.structure: SceneStructure = scene_structure(scene, bodies)
        # A mesh's file and scale are baked into the compiled vertices: the model's must stay.
        self._meshes = {(b.name, p.name): (p.mesh, np.array(p.size)) for b in bodies for p in b.parts if p.shape == "mesh"}
        self._scene = scene
        self._bodies = list(bodies)
        # Per object, the primitive that is all of it (sizes and masses written by `_write_primitives`), or None.
        self._shapes: list[str | None] = [primitive_shape(b.obj) for b in bodies]
        self._primitive_ids: dict[int, tuple[int, int]] = {}  # object -> (its body, its geom), once looked up
        self._groups: dict[tuple[int, ...], list[tuple[str, np.ndarray, np.ndarray]]] = {}  # `_primitive_groups`
        self._signatures: list[dict[str, Any]] | None = None  # of the scene applied last: all but poses and images
        self._image_names: list[Any] = []  # of the scene applied last, per object
        self._params: Any = None
        self._materials: dict[tuple[int, Any], int] = {}  # (object index, image name) -> material id
        self._textured_geoms = [np.array([model.geom(f"{b.name}/{p.name}").id for p in b.parts
                                          if p.texture is not None and p.shape != "mesh"], dtype=int) for b in bodies]
        # Objects are bodies or lights (a light of the world body, where the object is).
        self._is_light = np.array([b.light is not None for b in bodies], dtype=bool)
        self._body_ids = np.array([model.body(b.name).id for b in bodies if b.light is None], dtype=int)
        self._light_ids = np.array([model.light(b.name).id for b in bodies if b.light is not None], dtype=int)
        self._free = np.array([not b.fixed for b in bodies], dtype=bool)
        # Each free body's 7 qpos entries (position, quaternion), in scene order.
        self._free_qpos = np.array([model.jnt_qposadr[model.joint(b.name).id] + k
                                    for b in bodies if not b.fixed for k in range(7)], dtype=int)
        # The same, as slices where they are consecutive (`apply` writes through them every scene).
        self._body_rows = _as_slice(np.flatnonzero(~self._is_light))
        self._free_rows = _as_slice(np.flatnonzero(self._free))
        self._body_ids = _as_slice(self._body_ids)
        self._free_qpos = _as_slice(self._free_qpos)
        self._home = model.key("home").id if model.nkey else None
        # mj_setConst leaves `data` at `qpos_spring`, where the statistics are taken when it is `qpos0`.
        fixed = np.ones(model.nq, dtype=bool)
        fixed[self._free_qpos] = False
        self._spring_at_qpos0 = bool(np.array_equal(model.qpos_spring[fixed], model.qpos0[fixed]))
        self._statistics = _Statistics(model)
        self._robot_qpos = np.zeros(model.nq)
        self._robot_ctrl = np.zeros(model.nu)

    def apply(self, scene_json: Mapping[str, Any], data) -> None:
        """Write a scene into the model and `data`, then reset `data` to its `home` key and forward."""
        import mujoco

        model = self.model
        found = self._changed(scene_json)
        if found is None:
            self._apply_whole(scene_json)
        else:
            changed, resized = found
            if resized:
                self._resize(scene_json["objects"], resized)
            if changed:
                self._apply_objects(scene_json, changed)
        poses = self._poses(scene_json["objects"])
        bodies = poses[self._body_rows]
        model.body_pos[self._body_ids] = bodies[:, :3]
        model.body_quat[self._body_ids] = bodies[:, 3:]
        if len(self._light_ids):
            model.light_pos[self._light_ids] = poses[self._is_light, :3]
            model.light_dir[self._light_ids] = light_directions(poses[self._is_light, 3:])
        free = poses[self._free_rows].ravel()
        model.qpos0[self._free_qpos] = free
        model.qpos_spring[self._free_qpos] = free  # the compiler's copy of qpos0 for free joints
        home = self._home
        if home is not None:
            # The home key holds free bodies where they are and robots at their joints.
            key = model.key_qpos[home]
            key[:] = self._robot_qpos
            key[self._free_qpos] = free
            if model.nu:
                model.key_ctrl[home] = self._robot_ctrl
        mujoco.mj_setConst(model, data)
        if not self._spring_at_qpos0:  # mj_setConst leaves `data` at `qpos_spring`
            data.qpos[:] = model.qpos0
            mujoco.mj_kinematics(model, data)
        self._statistics.set(model, data)
        if home is not None:
            mujoco.mj_resetDataKeyframe(model, data, home)
        else:
            mujoco.mj_resetData(model, data)
        mujoco.mj_forward(model, data)

    def _poses(self, objects: list[Any]) -> np.ndarray:
        """Each object's position and unit quaternion (rows of 7, the quaternion normalised), validated
        as the scene parser does: all at once, and one by one (for the parser's message) when that fails."""
        try:
            positions = [raw["position"] for raw in objects]
            quaternions = [raw["quaternion"] for raw in objects]
            exact = set(map(type, chain.from_iterable(positions))) | set(map(type, chain.from_iterable(quaternions)))
            position, quaternion = np.array(positions, dtype=float), np.array(quaternions, dtype=float)
        except (KeyError, TypeError, ValueError):
            exact, position, quaternion = set(), None, None
        if exact <= {float, int} and position is not None and position.shape == (len(objects), 3) \
                and quaternion.shape == (len(objects), 4):
            poses = np.empty((len(objects), 7))
            poses[:, :3], poses[:, 3:] = position, quaternion
        else:
            poses = np.empty((0, 7))
        if len(poses) == len(objects) and np.isfinite(poses).all():
            q = poses[:, 3:]
            squares = (q * q).T
            norm = np.sqrt(squares[0] + squares[1] + squares[2] + squares[3])  # unit_quaternion's, in its order
            if np.abs(norm - 1.0).max(initial=0.0) <= 1e-6:
                q /= norm[:, None]
                return poses
        if not all(isinstance(raw, Mapping) for raw in objects):
            raise PrscError("scene JSON: objects: expected a list of objects")
        return np.array([scene_position(raw.get("position"), f"object {body.obj.label!r}.position")
                         + unit_quaternion(raw.get("quaternion"), f"object {body.obj.label!r}.quaternion")
                         for body, raw in zip(self._bodies, objects)], dtype=float).reshape(-1, 7)

    def _changed(self, scene_json: Mapping[str, Any]) -> tuple[list[int], dict[int, dict[str, Any]]] | None:
        """The objects to parse again, and the primitives whose dimensions and mass alone changed (with
        their signatures; an object whose image alone changed, to a known one, is switched here), or
        None when the whole scene must be read (the first, or another set of objects or params)."""
        objects = scene_json.get("objects") if _is_mapping(scene_json) else None
        if (self._signatures is None or not isinstance(objects, list) or len(objects) != len(self._signatures)
                or scene_json.get("params") != self._params):
            return None
        changed: list[int] = []
        resized: dict[int, dict[str, Any]] = {}
        for k, (raw, old) in enumerate(zip(objects, self._signatures)):
            signature = _signature(raw) if _is_mapping(raw) else None
            if signature != old:
                if signature is not None and self._shapes[k] is not None and _sized_alike(signature, old):
                    resized[k] = signature
                else:
                    changed.append(k)
                continue
            image = _image_name(raw)
            if image != self._image_names[k]:
                material = self._materials.get((k, image))
                if material is None:
                    changed.append(k)
                    continue
                self.model.geom_matid[self._textured_geoms[k]] = material
                self._image_names[k] = image
        return changed, resized

    def _resize(self, objects: list[Any], resized: Mapping[int, dict[str, Any]]) -> None:
        """Validate and write the new dimensions and mass of primitives whose JSON changed in nothing else."""
        numbers = _sizes_at_once(objects, resized, self._free)
        if numbers is None:  # one by one, for the scene parser's message
            where = [f"object {objects[k].get('name')!r}" for k in resized]
            numbers = (np.array([object_dimensions(objects[k].get("dimensions"), w) for k, w in zip(resized, where)]),
                       np.array([object_mass(objects[k].get("mass"), w, free=not self._bodies[k].fixed)
                                 for k, w in zip(resized, where)]))
        dimensions, masses = numbers
        # Its Body keeps the numbers it was resolved with: of a primitive's Body only its name and structure are read.
        self._write_primitives(list(resized), dimensions, masses)
        for k, signature in resized.items():
            self._signatures[k] = signature  # type: ignore[index]

    def _write_primitives(self, objects: list[int], dimensions: np.ndarray, masses: np.ndarray) -> None:
        """Geom size and bounds, body mass and inertia of primitive `objects` of `dimensions` and `masses`
        (rows), all of one shape at once (their geoms' pose, centre of mass and axes are the body's)."""
        model = self.model
        groups = self._primitive_groups(tuple(objects))
        for shape, rows, (bodies, geoms) in groups:
            if len(groups) > 1:
                group_dimensions, group_masses = dimensions[rows], masses[rows]
            else:
                group_dimensions, group_masses = dimensions, masses
            extents = primitive_extents(shape, group_dimensions)
            sizes = primitive_geom_sizes(shape, extents)
            model.geom_size[geoms] = sizes
            rbound, half = _bounds(shape, sizes)
            model.geom_rbound[geoms] = rbound
            aabb = np.zeros((len(sizes), 6))
            aabb[:, 3:] = half
            model.geom_aabb[geoms] = aabb
            model.body_mass[bodies] = group_masses
            model.body_inertia[bodies] = primitive_inertia(shape, extents, group_masses)

    def _primitive_groups(self, objects: tuple[int, ...]) -> list[tuple[str, np.ndarray, tuple[Any, Any]]]:
        """Primitive `objects` by shape: (shape, their rows in `objects`, their bodies' and geoms' ids, each a
        slice where they are consecutive), once per set of objects (a reset loop writes the same objects every scene)."""
        groups = self._groups.get(objects)
        if groups is None:
            shapes = [self._shapes[k] for k in objects]
            groups = self._groups[objects] = []
            for shape in dict.fromkeys(shapes):
                rows = [i for i, s in enumerate(shapes) if s == shape]
                ids = np.array([self._primitive_id(objects[i]) for i in rows], dtype=int).reshape(-1, 2)
                groups.append((shape, np.array(rows, dtype=int), (_as_slice(ids[:, 0]), _as_slice(ids[:, 1]))))  # type: ignore[arg-type]
        return groups

    def _primitive_id(self, k: int) -> tuple[int, int]:
        """The body and geom of primitive object `k`."""
        ids = self._primitive_ids.get(k)
        if ids is None:
            name = self._bodies[k].name
            ids = self._primitive_ids[k] = (self.model.body(name).id, self.model.geom(f"{name}/{self._shapes[k]}").id)
        return ids

    def _apply_objects(self, scene_json: Mapping[str, Any], changed: list[int]) -> None:
        """Parse, resolve and write only the objects in `changed` (the others are as applied last)."""
        objects = scene_json["objects"]
        bodies = list(self._bodies)
        for k in changed:
            if not isinstance(objects[k], Mapping) or objects[k].get("name") != bodies[k].obj.label:
                self._apply_whole(scene_json)  # another name: the whole scene says how it differs
                return
            bodies[k] = resolve_body(parse_object(objects[k], k, bodies[k].name), self._scene, self.store)
        fresh = scene_structure(self._scene, tuple(bodies[k] for k in changed)).objects
        objects_structure = list(self.structure.objects)
        for k, structure in zip(changed, fresh):
            objects_structure[k] = structure
        self._check(replace(self.structure, objects=tuple(objects_structure)), scene_json.get("index"))
        self._bodies = bodies
        for k in changed:
            self._write_body(k, bodies[k], objects[k])
        self._write_resolved_primitives(changed)
        if any(bodies[k].robot is not None for k in changed):
            self._robot_home()

    def _apply_whole(self, scene_json: Mapping[str, Any]) -> None:
        """Validate the scene and write everything but the poses: sizes, masses, colours, images, joints."""
        scene = parse_scene(scene_json)
        bodies = resolve_bodies(scene, self.store)
        self._check(scene_structure(scene, bodies), scene.index)
        self._signatures = [_signature(o) for o in scene_json["objects"]]
        self._image_names = [None] * len(bodies)
        self._params = scene_json.get("params")
        self._scene = scene
        self._bodies = list(bodies)
        for k, (body, raw) in enumerate(zip(bodies, scene_json["objects"])):
            self._write_body(k, body, raw)
        self._write_resolved_primitives(range(len(bodies)))
        self._robot_home()

    def _write_resolved_primitives(self, objects: Iterable[int]) -> None:
        """`_write_primitives` for the resolved bodies `objects` that are primitives."""
        chosen = [k for k in objects if self._shapes[k] is not None]
        if chosen:
            objs = [self._bodies[k].obj for k in chosen]
            self._write_primitives(chosen, np.array([o.dimensions for o in objs]), np.array([o.mass for o in objs]))

    def _check(self, structure: SceneStructure, index: Any) -> None:
        """Refuse a scene whose structure is not the model's, saying what differs."""
        why = difference(self.structure, structure)
        if why is not None:
            raise PrscError(f"scene {index} does not fit this spec's shared MuJoCo model: {why}")

    def _robot_home(self) -> None:
        """The robots' joints and servo targets of the home key, from the bodies applied."""
        robot_qpos = np.zeros(self.model.nq)
        ctrl: list[float] = []
        for body in self._bodies:
            if body.robot is None:
                continue
            fragment = robot_fragment(body.robot, f"{body.name}/", self.store, self.folder)
            joints, servo = self._robot_values(fragment, body)
            for name, value in zip(fragment.joints, joints):
                robot_qpos[self.model.jnt_qposadr[self.model.joint(f"{body.name}/{name}").id]] = value
            ctrl += servo
        self._robot_qpos = robot_qpos
        self._robot_ctrl = np.array(ctrl)

    @staticmethod
    def _robot_values(fragment: RobotFragment, body: Body) -> tuple[list[float], list[float]]:
        """The robot's qpos and ctrl in the home key, as numbers."""
        assert body.robot is not None
        qpos, ctrl = fragment.home(body.robot, dict(body.obj.joints))
        return [float(v) for v in qpos], [float(v) for v in ctrl]

    def _write_body(self, k: int, body: Body, raw: Mapping[str, Any]) -> None:
        """Mass properties, geoms, colours, images and camera of object `k` (its pose: `apply`)."""
        model = self.model
        obj = body.obj
        self._image_names[k] = _image_name(raw)
        self._signatures[k] = _signature(raw)
        shape = self._shapes[k] = primitive_shape(obj)
        if body.light is not None:
            light = model.light(obj.name).id
            model.light_diffuse[light] = body.light.diffuse
            model.light_cutoff[light] = body.light.cutoff
            model.light_castshadow[light] = body.light.cast_shadow
            return
        b = model.body(obj.name).id
        inertial = body.inertial
        model.body_ipos[b] = inertial.com
        model.body_iquat[b] = inertial.principal
        if shape is None:  # a primitive's mass, inertia and geom size: `_write_primitives`
            model.body_mass[b] = inertial.mass
            model.body_inertia[b] = inertial.diagonal
        for part in body.parts:
            g = model.geom(f"{obj.name}/{part.name}").id
            model.geom_pos[g] = part.position
            model.geom_quat[g] = part.quaternion
            model.geom_rgba[g] = geom_rgba(obj, part)
            if part.shape == "mesh":
                self._check_mesh(obj, part)
                continue
            if part.texture is not None:
                model.geom_matid[g] = self._material(obj.label, part.texture)
            if shape is None:
                size = np.array([geom_size(part)])
                model.geom_size[g] = size[0]
                rbound, half = _bounds(part.shape, size)
                model.geom_rbound[g] = rbound[0]
                model.geom_aabb[g] = np.concatenate([np.zeros(3), half[0]])
        if any(p.texture is not None and p.shape != "mesh" for p in body.parts):
            self._materials[(k, _image_name(raw))] = self._material(obj.label, next(
                p.texture for p in body.parts if p.texture is not None and p.shape != "mesh"))
        if body.camera is not None:
            model.cam_fovy[model.camera(obj.name).id] = body.camera.fovy

    def _material(self, label: str, image: str) -> int:
        """The material showing `image`, loaded when the model was built."""
        material = self._image_material.get(image)
        if material is None:
            raise PrscError(f"object {label!r} shows an image ({Path(image).name}) that is not among those its "
                            "spec can draw, which the shared model loaded; compile each scene")
        return material

    def _check_mesh(self, obj, part) -> None:
        """A mesh's file and scale are baked into its compiled vertices: neither may change."""
        label, mesh, scale = obj.label, part.mesh, np.array(part.size)
        first_mesh, first_scale = self._meshes[(obj.name, part.name)]
        if mesh != first_mesh:
            raise PrscError(f"object {label!r} is another mesh ({mesh}) than in the model ({first_mesh}); "
                            "a shared model cannot change a mesh: compile each scene")
        if not np.allclose(first_scale, scale, rtol=0, atol=1e-12):
            raise PrscError(f"object {label!r} is a mesh whose size changes between scenes ({first_scale.tolist()} in "
                            f"the model, {scale.tolist()} here); a shared model cannot rescale a mesh: compile each scene")
