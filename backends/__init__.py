"""Backends: one emitter per output format, each a function from the scene JSON to files.

Every backend module exposes `render(scene, path, store)`: `scene` a validated
`prsc.backends.scene.Scene`, `path` where the output will live (relative paths inside it are
computed from there), `store` the `prsc.backends.store.AssetStore` of shared meshes and robot
assets. It returns the file's bytes, or for a bundle a dict of relative name -> bytes.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping

from prsc.backends.scene import Scene, parse_scene
from prsc.backends.store import AssetStore


@dataclass(frozen=True)
class Target:
    """An output format: its backend module, file suffix, whether it is a bundle folder, and whether
    its output holds the scene's task itself (else a `<index>.task.json` file goes beside it)."""

    name: str
    module: str
    suffix: str
    bundle: bool = False
    task_inside: bool = False  # the scene JSON's "task" key; a bundle's task.json (docs/tasks.md)

    def render(self) -> Callable[[Scene, Path, AssetStore], Any]:
        """The backend's render function (imported on first use)."""
        return importlib.import_module(self.module).render

    def filename(self, index: int, width: int) -> str:
        """File (or bundle folder) name of scene `index`, zero-padded to `width` digits."""
        return f"{index:0{width}d}{self.suffix}"


TARGETS: dict[str, Target] = {
    "json": Target("json", "prsc.backends.json", ".json", task_inside=True),
    "mjcf": Target("mjcf", "prsc.backends.mjcf", ".xml"),
    "urdf": Target("urdf", "prsc.backends.urdf", "", bundle=True, task_inside=True),
    "sdf": Target("sdf", "prsc.backends.sdf", ".sdf"),
    "usd": Target("usd", "prsc.backends.usd", ".usda"),
}
"""Every output format, by the name `prsc compile --target` takes."""


def render_scene(raw: Mapping[str, Any], target: str, path: Path, store: AssetStore) -> Any:
    """Validate a scene JSON dict and render it with one backend."""
    return TARGETS[target].render()(parse_scene(raw), Path(path), store)
