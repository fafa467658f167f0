"""Asset registry: model name -> recipe fitting the asset to an object's box.

Part assets are lists of primitives (prsc.assets.parts.Part) in the object's box frame;
robot assets are the model library's arms (prsc/user_assets/asset_fitting.py), read from
their files as any URDF is (prsc.assets.articulated). Names are matched case- and separator-insensitively, so the
original ProbRobScene `model_name "DiningChair"` finds `diningchair` (alias `chair`).
"""

from __future__ import annotations

import functools
import re
from typing import Callable

from prsc.assets.camera_body import camera_parts
from prsc.assets.open_containers import container_parts
from prsc.assets.furniture import chair_parts, shelf_parts
from prsc.assets.parts import Part
from prsc.assets.solids import bottle_parts, cube_parts, cylinder_parts
from prsc.assets.table import table_parts
from prsc.geometry.container import ASSET_INTERIORS, asset_interior
from prsc.user_assets.asset_fitting import library_arm

Recipe = Callable[[tuple[float, float, float]], tuple[Part, ...]]


def _container_recipe(model: str) -> Recipe:
    """A container asset built from its own interior (prsc.geometry.container.ASSET_INTERIORS)."""
    return lambda dimensions: container_parts(asset_interior(model, dimensions))


# Each recipe is a pure function of the box, and a dataset asks it for the same few boxes in
# every scene: the parts are built once per box (frozen tuples, shared by every scene).
PART_ASSETS: dict[str, Recipe] = {model: functools.lru_cache(maxsize=256)(recipe) for model, recipe in {
    **{model: _container_recipe(model) for model in ASSET_INTERIORS},
    "table": table_parts,
    "shelf": shelf_parts,
    "cube": cube_parts,
    "cylinder": cylinder_parts,
    "bottle": bottle_parts,
    "diningchair": chair_parts,
    "chair": chair_parts,
    "camera": camera_parts,
}.items()}
"""Rigid assets built from primitives, by normalised model name."""



@functools.lru_cache(maxsize=1024)
def normalise_model(name: str) -> str:
    """Lower case without separators: 'DiningChair', 'dining_chair' -> 'diningchair'."""
    return re.sub(r"[^a-z0-9]", "", name.lower())


def part_recipe(model: str) -> Recipe | None:
    """The part recipe for a model name, or None when it is not a part asset."""
    return PART_ASSETS.get(normalise_model(model))


def is_robot(model: str | None) -> str | None:
    """The canonical robot name when `model` names a robot asset, else None."""
    if model is None:
        return None
    key = normalise_model(model)
    return key if library_arm(key) is not None else None


def is_hollow(model: str | None) -> bool:
    """Whether a model name is a container asset (built as a floor and walls)."""
    return model is not None and normalise_model(model) in ASSET_INTERIORS
