"""JSON backend: the scene JSON itself, one file per scene (`prsc-scene` version 1)."""

from __future__ import annotations

import json
from pathlib import Path

from prsc.backends.scene import Scene
from prsc.backends.store import AssetStore


def render(scene: Scene, path: Path, store: AssetStore) -> bytes:
    """Backend entry point: the scene JSON, keys in the sampler's order, one top-level key and
    one object per line (as docs/scene-json.md shows it). Each line is written by json's C
    encoder: `indent` would take its pure-Python one, 1 ms a scene, most of a JSON compile."""
    lines = []
    for key, value in scene.raw.items():
        if key == "objects" and isinstance(value, list) and value:
            objects = ",\n  ".join(_compact(o) for o in value)
            lines.append(f" {_compact(key)}: [\n  {objects}\n ]")
        else:
            lines.append(f" {_compact(key)}: {_compact(value)}")
    return ("{\n" + ",\n".join(lines) + "\n}\n").encode("utf-8")


def _compact(value: object) -> str:
    """One JSON value on one line (NaN and infinities refused, as scene JSON allows none)."""
    return json.dumps(value, allow_nan=False)
