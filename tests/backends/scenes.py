"""Hand-made scene JSONs for the backend tests (what the sampler would produce)."""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path

DATA = Path(__file__).resolve().parents[1] / "data"


def yaw_quat(degrees: float) -> list[float]:
    """Quaternion (w x y z) of a rotation about +z."""
    half = math.radians(degrees) / 2
    return [math.cos(half), 0.0, 0.0, math.sin(half)]


def axis_quat(axis, degrees: float) -> list[float]:
    """Quaternion (w x y z) of a rotation about an axis."""
    norm = math.sqrt(sum(a * a for a in axis))
    half = math.radians(degrees) / 2
    s = math.sin(half) / norm
    return [math.cos(half), axis[0] * s, axis[1] * s, axis[2] * s]


def obj(name, cls, position, dimensions, *, quaternion=(1.0, 0.0, 0.0, 0.0), static=False, mass=None,
        color=(0.5, 0.5, 0.5, 1.0), shape="box", model=None, camera=None, properties=None) -> dict:
    """One scene object; mass defaults to 500 kg/m^3 times the box volume."""
    w, l, h = dimensions
    return {
        "name": name, "class": cls, "position": list(position), "quaternion": list(quaternion),
        "dimensions": list(dimensions), "static": static,
        "mass": 500.0 * w * l * h if mass is None else mass,
        "color": list(color), "shape": shape, "model": model, "camera": camera,
        "properties": dict(properties or {}),
    }


def scene(objects, *, index=0, ground=True, spec="tests/backends/handmade.prs") -> dict:
    """A scene JSON document."""
    return {"format": "prsc-scene", "version": 1, "spec": spec, "seed": 0, "index": index,
            "params": {"ground": ground}, "objects": list(objects)}


def table_cube() -> dict:
    """The hand-made Table-Cube scene (two Pandas, trays, a cube in a tray, a camera)."""
    return json.loads((DATA / "table_cube_scene.json").read_text())


def on_ground(dimensions, x, y):
    """Position of a box resting on the ground at (x, y)."""
    return (x, y, dimensions[2] / 2)


def every_shape(mesh_path: str) -> dict:
    """Box, cylinder, sphere and mesh shapes resting on the ground, some rotated about z."""
    objects = [
        obj("box_a", "Box", on_ground((0.1, 0.2, 0.05), 0, 0), (0.1, 0.2, 0.05), quaternion=yaw_quat(30), color=(1, 0, 0, 1)),
        obj("cyl_a", "Cylinder", on_ground((0.08, 0.08, 0.12), 0.4, 0), (0.08, 0.08, 0.12), shape="cylinder", color=(0, 1, 0, 1)),
        obj("ball_a", "Ball", on_ground((0.06, 0.06, 0.06), 0, 0.4), (0.06, 0.06, 0.06), shape="sphere", color=(0, 0, 1, 1)),
        obj("mesh_a", "Thing", on_ground((0.1, 0.15, 0.08), 0.4, 0.4), (0.1, 0.15, 0.08), quaternion=yaw_quat(-70),
            shape="mesh", properties={"mesh": mesh_path}, color=(1, 1, 0, 1)),
        # Lying on its side: a box turned 90 degrees about x still rests on a face.
        obj("box_side", "Box", (-0.4, 0.0, 0.1), (0.05, 0.2, 0.3), quaternion=axis_quat((1, 0, 0), 90)),
        obj("wall", "Wall", (0.0, -0.5, 0.25), (1.0, 0.05, 0.5), static=True, color=(0.3, 0.3, 0.3, 1)),
    ]
    return scene(objects)


def every_model() -> dict:
    """Every part asset resting on the ground in a row, plus an unknown model."""
    models = [
        ("Tray", "tray", (0.2364, 0.4522, 0.028964)), ("Bin", "bin", (0.4, 0.3, 0.2)), ("Box", "box", (0.3, 0.3, 0.3)),
        ("Bowl", "bowl", (0.258534, 0.258564, 0.115678)), ("Cup", "cup", (0.09, 0.09, 0.1233)),
        ("Bucket", "bucket", (0.23494, 0.23495, 0.28436)), ("Plate", "plate", (0.40073, 0.40073, 0.036588)),
        ("Bottle", "bottle", (0.07, 0.07, 0.25)), ("Cube", "cube", (0.04, 0.04, 0.04)),
        ("Cylinder", "cylinder", (0.05, 0.05, 0.05)),
        ("DiningChair", "DiningChair", (0.40006, 0.45002, 0.90879)), ("Shelf", "shelf", (0.8, 0.3, 1.2)),
        ("Table", "table", (1.0, 0.6, 0.7)), ("Gadget", "hexagonal_gear", (0.14186, 0.1638, 0.017663)),
    ]
    objects, x = [], -4.0
    for k, (cls, model, dims) in enumerate(models):
        x += dims[0] / 2 + 0.1
        static = cls in ("Shelf", "Table", "DiningChair")
        objects.append(obj(f"{cls.lower()}_{k}", cls, on_ground(dims, x, 0.0), dims, model=model, static=static,
                           quaternion=yaw_quat(15 * k)))
        x += dims[0] / 2 + 0.1
    return scene(objects)


def tray_with_cube() -> dict:
    """A rotated tray on the ground with a cube resting on its rim plane (it drops in)."""
    tray_dims = (0.2364, 0.4522, 0.028964)
    q = yaw_quat(40)
    return scene([
        obj("tray", "Tray", on_ground(tray_dims, 0.2, 0.1), tray_dims, model="tray", quaternion=q),
        obj("cube", "Cube", (0.2, 0.1, tray_dims[2] + 0.02), (0.04, 0.04, 0.04), model="cube", color=(1, 0, 0, 1),
            quaternion=yaw_quat(10), mass=0.032),
    ])


def cube_in_air(height: float = 0.05) -> dict:
    """A free cube `height` metres above the ground and a camera looking at it from the side."""
    return scene([
        obj("cube", "Cube", (0.0, 0.0, 0.02 + height), (0.04, 0.04, 0.04), model="cube", mass=0.032, color=(0, 0, 1, 1)),
        obj("cam", "Camera", (0.0, -0.8, 0.3), (0.2, 0.4, 0.1), static=True, model="camera",
            camera={"fovy": 45.0, "resolution": [320, 240]}, quaternion=axis_quat((1, 0, 0), -15)),
    ])


def rotated_robot() -> dict:
    """A Panda on a rotated stand-in box (no table), yawed 60 degrees, with a cube ahead."""
    dims = (0.14, 0.22, 1.025562)
    q = yaw_quat(60)
    return scene([
        obj("arm", "Robot", (0.1, -0.2, dims[2] / 2), dims, static=True, model="panda", quaternion=q, mass=15.8),
        obj("cube", "Cube", (-0.4, 0.2, 0.02), (0.04, 0.04, 0.04), model="cube", mass=0.032),
    ])


def no_ground() -> dict:
    """`param ground = False`: a static shelf, nothing else."""
    return scene([obj("shelf", "Shelf", (0, 0, 0.6), (0.8, 0.3, 1.2), static=True, model="shelf")], ground=False)


def all_handmade(mesh_path: str) -> dict[str, dict]:
    """Every hand-made scene by name (deep copies)."""
    return copy.deepcopy({
        "table_cube": table_cube(),
        "every_shape": every_shape(mesh_path),
        "every_model": every_model(),
        "tray_with_cube": tray_with_cube(),
        "cube_in_air": cube_in_air(),
        "rotated_robot": rotated_robot(),
        "no_ground": no_ground(),
    })
