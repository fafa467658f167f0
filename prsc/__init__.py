"""prsc: a compiler for probabilistic 3D scene specifications for robot manipulation.

The library API, for a user's own loop (an RL reset, a test script) that wants scenes
without writing files:

    scenario = prsc.load("specs/table_cube.prs")
    scene = scenario.scene(seed=0, index=7)     # scene JSON (docs/scene-json.md)
    model = prsc.mujoco_model(scene)            # a mujoco.MjModel, built in memory

Everything is imported on first use, so `import prsc` stays cheap.
"""

from __future__ import annotations

import os
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

if TYPE_CHECKING:
    import mujoco

    from prsc.sampling import Sampler

__all__ = ["load", "mjcf_text", "mujoco_model", "mujoco_spec"]


def load(path: str | os.PathLike[str], include_dirs: Sequence[str | os.PathLike[str]] = ()) -> Sampler:
    """Compile a .prs spec; `.scene(seed, index)` of the result draws scene JSON, as `prsc sample` does."""
    from prsc.sampling import compile_sampler

    return compile_sampler(path, include_dirs=include_dirs)


def _cache() -> Path:
    """Where in-memory models find their meshes: an asset store in the build folder
    (`$PRSC_BUILD_DIR/in-memory`, beside the converted robot assets)."""
    from prsc.assets.panda import build_dir

    return build_dir().parent / "in-memory"


def mjcf_text(scene: dict[str, Any]) -> str:
    """The MJCF text `prsc compile --target mjcf` writes for a scene (meshes at ../assets/, as in its output)."""
    from prsc.backends.mjcf import mjcf_xml
    from prsc.backends.scene import parse_scene
    from prsc.backends.store import AssetStore

    root = _cache()
    return mjcf_xml(parse_scene(scene), root / "mjcf" / "scene.xml", AssetStore(root / "assets"))


@lru_cache(maxsize=256)
def _file_bytes(path: str, mtime_ns: int) -> bytes:
    return Path(path).read_bytes()


def mujoco_spec(scene: dict[str, Any]) -> mujoco.MjSpec:
    """The scene's MjSpec, parsed from `mjcf_text` with its meshes given in memory.

    `spec.to_xml()` equals `mujoco.MjSpec.from_file(f).to_xml()` for the file `f` that
    `prsc compile` writes, and `spec.compile()` the model MuJoCo loads from it."""
    import xml.etree.ElementTree as ET

    import mujoco

    text = mjcf_text(scene)
    folder = _cache() / "mjcf"
    assets = {}
    for element in ET.fromstring(text).iter():
        name = element.get("file")
        if name and name not in assets:
            path = os.path.normpath(folder / name)
            assets[name] = _file_bytes(path, os.stat(path).st_mtime_ns)
    return mujoco.MjSpec.from_string(text, assets=assets)


def mujoco_model(scene: dict[str, Any]) -> mujoco.MjModel:
    """A `mujoco.MjModel` of a scene, built in memory: the model of the file `prsc compile` writes."""
    return mujoco_spec(scene).compile()
