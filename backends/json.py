"""JSON backend: the scene JSON itself, one file per scene (`prsc-scene` version 1)."""

from __future__ import annotations

import json
from pathlib import Path

from prsc.backends.scene import Scene
from prsc.backends.store import AssetStore


def render(scene: Scene, path: Path, store: AssetStore) -> bytes:
    """Backend entry point: the scene JSON, indented, keys in the sampler's order."""
    return (json.dumps(scene.raw, indent=1, allow_nan=False) + "\n").encode("utf-8")
