"""The library API behind `prsc.load` (docs/learning.md): a compiled spec that draws scenes,
builds their MuJoCo model in memory, and writes a new scene into one shared model without
recompiling it (an RL reset)."""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterable, Iterator

if TYPE_CHECKING:
    import mujoco

    from prsc.backends.shared_model import SharedModel
    from prsc.sampling import Sampler


RESET_DRAW_AHEAD = 64
"""A reset loop's first draw (SceneEnv's `draw_ahead`): a seeded reset redraws this many scenes. Where
the spec draws by Gibbs rounds, numpy calls per round cost most: 64 scenes cost 1.8x 16 (90 against
49 ms on specs/bin_ten_parts.prs), so a loop's draws cost 4-13 % less from 64 than from 16 over
10 to 4,000 resets (docs/learning.md, "Packed resets, cut again"); a loop that reseeds every
episode may pass 16 or less."""
RESET_DRAW_AHEAD_MAX = 256
"""Where a reset loop's draws stop doubling (SceneEnv's `draw_ahead_max`): the steady batch."""


def in_memory_root() -> Path:
    """Where in-memory models find their meshes: an asset store in the build folder
    (`$PRSC_BUILD_DIR/in-memory`, beside the converted robot assets)."""
    from prsc.user_assets.asset_files import build_root

    return build_root() / "in-memory"


def mjcf_text(scene: dict[str, Any]) -> str:
    """The MJCF text `prsc compile --target mjcf` writes for a scene (meshes at ../assets/, as in its output)."""
    from prsc.backends.mjcf import mjcf_xml
    from prsc.backends.scene import parse_scene
    from prsc.backends.store import AssetStore

    root = in_memory_root()
    return mjcf_xml(parse_scene(scene), root / "mjcf" / "scene.xml", AssetStore(root / "assets"))


@lru_cache(maxsize=256)
def _file_bytes(path: str, mtime_ns: int) -> bytes:
    return Path(path).read_bytes()


def mujoco_spec(scene: dict[str, Any]) -> mujoco.MjSpec:
    """The scene's MjSpec, parsed from `mjcf_text` with its meshes given in memory.

    `spec.to_xml()` equals `mujoco.MjSpec.from_file(f).to_xml()` for the file `f` that
    `prsc compile` writes, and `spec.compile()` the model MuJoCo loads from it."""
    import mujoco

    text = mjcf_text(scene)
    folder = in_memory_root() / "mjcf"
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


def load(path: str | os.PathLike[str], include_dirs: Iterable[str | os.PathLike[str]] = ()) -> "Scenario":
    """Compile a .prs spec into a Scenario (`prsc.load`)."""
    from prsc.sampling import compile_sampler

    return Scenario(compile_sampler(path, include_dirs=tuple(include_dirs)))


class Scenario:
    """A compiled spec: scenes as JSON, their MuJoCo model, and resets without recompiling."""

    def __init__(self, sampler: Sampler) -> None:
        self.sampler = sampler
        self._shared: dict[int, SharedModel] = {}  # id(model) -> how to write scenes into it

    def __getattr__(self, name: str) -> Any:
        # Everything else a Sampler offers (sample, to_json, law, spec, ...).
        return getattr(self.sampler, name)

    def scene(self, seed: int, index: int) -> dict[str, Any]:
        """Scene `index` under `seed` as scene JSON (docs/scene-json.md), as `prsc run` hands it
        to a controller: each object with its `body`, its name in the compiled model."""
        from prsc.backends.names import with_body_names

        return with_body_names(self.sampler.scene(seed, index))

    def scenes(self, seed: int, indices: Iterable[int] | int, start: int = 0) -> Iterator[dict[str, Any]]:
        """Scenes `indices` (or `start .. start+n-1` for an int n) under `seed`, lazily; drawn in
        batches, vectorised over scenes, when the spec allows it (docs/sampling.md, "Batched sampling");
        each as `scene` gives it."""
        from prsc.backends.names import with_body_names

        return map(with_body_names, self.sampler.scenes(seed, indices, start))

    def drawer(self, seed: int, ahead: int = 64, grow_to: int | None = None) -> Callable[[int], dict[str, Any]]:
        """index -> scene under `seed`, as `scene` gives it, drawn `ahead` at a time where the spec batches
        (with `grow_to`: each draw twice the last, up to `grow_to`; `Sampler.drawer`)."""
        from prsc.backends.names import with_body_names

        draw = self.sampler.drawer(seed, ahead, grow_to)
        return lambda index: with_body_names(draw(index))

    def image_choices(self) -> dict[str, tuple[str, ...]]:
        """Per object whose `texture` is a file name or a choice among file names, every name it can
        draw (`prsc check` refuses any other texture; the shared model refuses an object it lacks)."""
        from prsc.ir.mesh_sizes import constant_strings

        choices = {}
        for obj in self.sampler.program.objects:
            texture = obj.prop("texture")
            names = None if texture is None else constant_strings(texture)
            if names is not None:
                choices[obj.name] = names
        return choices

    def model(self, seed: int = 0, index: int = 0) -> mujoco.MjModel:
        """One MjModel whose structure fits every scene of the spec (built from scene `index` of `seed`),
        with every image the spec can draw loaded once."""
        from prsc.backends.shared_model import SharedModel
        from prsc.backends.store import AssetStore

        scene = self.scene(seed, index)
        root = in_memory_root()
        shared = SharedModel(scene, mujoco_spec(scene), AssetStore(root / "assets"), root / "mjcf", self.image_choices())
        self._shared[id(shared.model)] = shared
        return shared.model

    def apply(self, scene: dict[str, Any], model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Write `scene` into `model` (from `model()`) and `data` without recompiling, then reset
        `data` to the scene's `home` key and `mj_forward` (docs/learning.md)."""
        from prsc.errors import PrscError

        shared = self._shared.get(id(model))
        if shared is None or shared.model is not model:
            raise PrscError("apply writes into a model this scenario built: use scenario.model()")
        shared.apply(scene, data)
