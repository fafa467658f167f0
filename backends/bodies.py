"""What every format needs per object: its parts, mass properties, robot mount and camera."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from prsc.assets.open_containers import container_parts
from prsc.assets.parts import Part
from prsc.assets.articulated import RobotModel, robot_model
from prsc.assets.registry import normalise_model, part_recipe
from prsc.user_assets.asset_files import ROOT_OFFSET, names_asset_file
from prsc.backends.inertia import PRIMITIVES, Inertial, composite_inertial
from prsc.backends.scene import CameraSpec, LightSpec, Scene, SceneObject
from prsc.backends.store import AssetStore, pbr_maps, texture_of
from prsc.errors import PrscError
from prsc.geometry.container import Interior, declared_interior
from prsc.user_assets.mesh_paths import MESH_COLLISIONS, TEXTURED_SHAPES, mesh_folders, resolve_mesh

CAMERA_QUAT_NEG_Z = (0.7071067811865476, 0.7071067811865476, 0.0, 0.0)
"""Rotation (w x y z, object frame) of a camera that looks along its local -Z with +Y up
(MuJoCo, USD) so that it looks along the object's +y with image up = the object's +z."""

CAMERA_QUAT_POS_X = (0.7071067811865476, 0.0, 0.0, 0.7071067811865476)
"""Rotation of a camera that looks along its local +X with +Z up (SDF/Gazebo)."""


MOUNT_INERTIAL = Inertial(
    mass=0.001, com=(0.0, 0.0, 0.0), tensor=((1e-6, 0.0, 0.0), (0.0, 1e-6, 0.0), (0.0, 0.0, 1e-6)),
    diagonal=(1e-6, 1e-6, 1e-6), principal=(1.0, 0.0, 0.0, 0.0),
)
"""A robot object's own body is a near-massless mount (its links carry the mass); the
simulators still want a positive mass on it when the robot is free-floating."""


class UnknownModelWarning(UserWarning):
    """An object names a model no backend knows; it is written as its plain shape."""


_warned_classes: set[str] = set()


@dataclass(frozen=True)
class Body:
    """One object resolved for the backends: its geometry, mass properties and extras."""

    obj: SceneObject
    parts: tuple[Part, ...]  # empty for a robot: the robot model is its geometry
    inertial: Inertial  # MOUNT_INERTIAL for a robot (its links carry their own)
    robot: RobotModel | None  # an articulated asset: a URDF/MJCF file (the user's or a library arm's)
    camera: CameraSpec | None

    @property
    def name(self) -> str:
        """The object's name, which names the body in every format."""
        return self.obj.name

    @property
    def fixed(self) -> bool:
        """Fixed in the world: a static object, a camera (always fixed where sampled) or a light."""
        return self.obj.static or self.obj.camera is not None or self.obj.light is not None

    @property
    def light(self) -> LightSpec | None:
        """The light this object is (a light has no body in any format), or None."""
        return self.obj.light

    @property
    def mount_position(self) -> tuple[float, float, float]:
        """The robot's root frame in the object frame (RobotModel.mount_position)."""
        assert self.robot is not None
        return self.robot.mount_position(self.obj.dimensions, self.obj.properties.get(ROOT_OFFSET))


def reset_model_warnings() -> None:
    """Forget which classes were warned about (a new compile run warns afresh)."""
    _warned_classes.clear()


def _warn_unknown_model(obj: SceneObject) -> None:
    """Warn once per class (per process) that an unknown model falls back to its shape."""
    if obj.cls in _warned_classes:
        return
    _warned_classes.add(obj.cls)
    warnings.warn(
        UnknownModelWarning(
            f"class {obj.cls}: unknown model {obj.model!r}; objects of this class are written as a plain {obj.shape}"
        ),
        stacklevel=3,
    )


def resolve_mesh_source(obj: SceneObject, scene: Scene, store: AssetStore, prop: str = "mesh") -> Path:
    """The file an object's `prop` (its mesh, its texture) names: in the spec's folder or the
    store's --include folders."""
    folders = mesh_folders(scene.spec, store.mesh_dirs)
    try:
        return resolve_mesh(str(obj.properties[prop]), folders, store.meshes_anywhere, what=prop)
    except PrscError as error:
        raise PrscError(f"object {obj.label or obj.name!r}: {error.message}", obj=obj.label or obj.name) from None


PLAIN_SHAPE_MODELS = {"cube": "box", "cylinder": "cylinder"}
"""Part assets that are one primitive filling the object's box (prsc.assets.solids), by normalised model name."""


def primitive_shape(obj: SceneObject) -> str | None:
    """The primitive (box, cylinder, sphere) that is all of the object's geometry, filling or inscribed
    in its box (no robot, camera, light, container interior or image), else None: then its part and
    mass properties are formulas of its dimensions and mass (`primitive_extents`, `primitive_inertia`)."""
    if obj.light is not None or obj.camera is not None or "texture" in obj.properties:
        return None
    shape = obj.shape if obj.model is None else PLAIN_SHAPE_MODELS.get(normalise_model(obj.model))
    if shape not in PRIMITIVES or object_interior(obj) is not None:
        return None
    return shape


def primitive_extents(shape: str, dimensions: np.ndarray) -> np.ndarray:
    """Full extents (rows x y z) of the `shape` parts of boxes `dimensions` (rows): a box fills its
    box, a z-axis cylinder and a sphere are inscribed in it."""
    dims = np.asarray(dimensions, dtype=float).reshape(-1, 3)
    if shape == "box":
        return dims
    across = np.minimum(dims[:, 0], dims[:, 1]) if shape == "cylinder" else dims.min(axis=1)
    extents = np.empty_like(dims)  # columns written: np.stack costs more than the numbers (a reset writes these)
    extents[:, 0], extents[:, 1], extents[:, 2] = across, across, dims[:, 2] if shape == "cylinder" else across
    return extents


def primitive_part(shape: str, dimensions: tuple[float, float, float]) -> Part:
    """The one part of an object of `primitive_shape` `shape` and box `dimensions`, named as its shape."""
    return Part(shape, shape, tuple(float(v) for v in primitive_extents(shape, dimensions)[0]))  # type: ignore[arg-type]


def shape_parts(obj: SceneObject, scene: Scene, store: AssetStore) -> tuple[Part, ...]:
    """The object's own shape (box, cylinder, sphere or mesh) filling or inscribed in its box."""
    if obj.shape in PRIMITIVES:
        return (primitive_part(obj.shape, obj.dimensions),)
    source = resolve_mesh_source(obj, scene, store)
    collision = str(obj.properties.get("collision", "hull")).strip().lower()
    try:
        if collision not in MESH_COLLISIONS:
            raise PrscError(f"collision {obj.properties['collision']!r} is not one of {', '.join(MESH_COLLISIONS)}")
        mesh = store.normalised_mesh(source, str(obj.properties.get("upAxis", "+z")))
        texture = texture_of(mesh)
        image = None if texture is None else str(texture)
        seen = Part("mesh", "mesh", obj.dimensions, mesh=str(mesh), texture=image, maps=pbr_maps(image))
        if collision == "hull":
            return (seen,)
        pieces = store.convex_pieces(mesh)
    except PrscError as error:
        raise PrscError(f"object {obj.label or obj.name!r}: {error.message}", obj=obj.label or obj.name) from None
    # The mesh is seen; its convex pieces (in the same unit-cube frame, so the same scale)
    # collide and are not drawn.
    return (replace(seen, collides=False),
            *(Part(f"piece{k:02d}", "mesh", obj.dimensions, mesh=str(p), visible=False) for k, p in enumerate(pieces)))


def object_interior(obj: SceneObject) -> Interior | None:
    """The container interior the object declares (floor and walls where things rest), if any."""
    try:
        return declared_interior(obj.dimensions, obj.properties)
    except ValueError as error:
        raise PrscError(f"object {obj.label or obj.name!r}: {error}", obj=obj.label or obj.name) from None


def resolve_body(obj: SceneObject, scene: Scene, store: AssetStore) -> Body:
    """Resolve one object: asset recipe, robot or plain shape, and its mass properties."""
    if obj.light is not None:
        return Body(obj, (), MOUNT_INERTIAL, None, None)
    shape = primitive_shape(obj)
    if shape is not None:
        parts = (primitive_part(shape, obj.dimensions),)
        return Body(obj, parts, composite_inertial(parts, obj.mass), None, None)
    try:
        # A file asset is a robot when the scene gives it a `tcp` (every Robot subclass does).
        folders = mesh_folders(scene.spec, store.mesh_dirs) if obj.model is not None and names_asset_file(obj.model) else ()
        robot = robot_model(obj.model, folders, passive="tcp" not in obj.properties)
    except PrscError as error:
        raise PrscError(f"object {obj.label or obj.name!r}: {error.message}", obj=obj.label or obj.name) from None
    if robot is not None and obj.camera is None:
        return Body(obj, (), MOUNT_INERTIAL, robot, None)
    parts: tuple[Part, ...] | None = None
    interior = object_interior(obj)
    if obj.model is not None:
        recipe = part_recipe(obj.model)
        if recipe is not None:
            parts = recipe(obj.dimensions) if interior is None else container_parts(interior)
        else:
            _warn_unknown_model(obj)  # an unknown model stays its box, declared interior or not
    elif interior is not None:
        parts = container_parts(interior)
    if parts is None:
        if obj.camera is not None and obj.model is None:
            parts = part_recipe("camera")(obj.dimensions)  # type: ignore[misc]
        else:
            parts = shape_parts(obj, scene, store)
    if obj.camera is not None:
        # A camera is a sensor: whatever its housing looks like, it never collides.
        parts = tuple(replace(p, collides=False) for p in parts)
    if "texture" in obj.properties:
        parts = _textured(parts, obj, scene, store)
    return Body(obj, parts, composite_inertial(parts, obj.mass), None, obj.camera)


def texture_image(obj: SceneObject, scene: Scene, store: AssetStore) -> str:
    """The store's copy of the image an object's `texture` names (absolute path)."""
    source = resolve_mesh_source(obj, scene, store, "texture")
    try:
        return str(store.texture_image(source))
    except PrscError as error:
        raise PrscError(f"object {obj.label or obj.name!r}: {error.message}", obj=obj.label or obj.name) from None


def _textured(parts: tuple[Part, ...], obj: SceneObject, scene: Scene, store: AssetStore) -> tuple[Part, ...]:
    """`with texture`: the image on the object's visible boxes, cylinders and spheres."""
    image = texture_image(obj, scene, store)
    return tuple(replace(p, texture=image) if p.shape in TEXTURED_SHAPES and p.visible else p for p in parts)


def resolve_bodies(scene: Scene, store: AssetStore) -> tuple[Body, ...]:
    """Resolve every object of a scene, in scene order."""
    return tuple(resolve_body(obj, scene, store) for obj in scene.objects)


def light_directions(quaternions: np.ndarray) -> np.ndarray:
    """Where lights of these orientations (w x y z, one per row) shine: their local +y in the world."""
    w, x, y, z = np.asarray(quaternions, dtype=float).reshape(-1, 4).T
    directions = np.stack([2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)], axis=1)
    return directions / np.linalg.norm(directions, axis=1, keepdims=True)


def object_matrix(obj: SceneObject) -> np.ndarray:
    """The object's 4x4 pose in the world (box centre, orientation)."""
    from prsc.geometry.rotations import quat_to_matrix

    out = np.eye(4)
    out[:3, :3] = quat_to_matrix(obj.quaternion)
    out[:3, 3] = obj.position
    return out
