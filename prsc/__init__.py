"""prsc: a compiler for probabilistic 3D scene specifications for robot manipulation.

The library API, for a user's own loop (an RL reset, a test script) that wants scenes
without writing files:

    scenario = prsc.load("specs/table_cube.prs")
    scene = scenario.scene(seed=0, index=7)     # scene JSON (docs/scene-json.md)
    model = prsc.mujoco_model(scene)            # a mujoco.MjModel, built in memory

    model = scenario.model()                    # one model for every scene of the spec
    data = mujoco.MjData(model)
    scenario.apply(scenario.scene(0, 8), model, data)   # a reset, no recompiling

    env = prsc.SceneEnv("specs/table_cube.prs")  # a gymnasium.Env (pip install 'prsc[gym]')
    env = prsc.RecordEpisodes(env, "out/demos", format="lerobot")  # its episodes as a dataset

Everything is imported on first use, so `import prsc` stays cheap.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any, Sequence

if TYPE_CHECKING:
    import mujoco

    from prsc.scenario import Scenario

__all__ = ["load", "mjcf_text", "mujoco_model", "mujoco_spec", "SceneEnv", "RecordEpisodes"]


def load(path: str | os.PathLike[str], include_dirs: Sequence[str | os.PathLike[str]] = ()) -> Scenario:
    """Compile a .prs spec; `.scene(seed, index)` of the result draws scene JSON, as `prsc sample` does."""
    from prsc.scenario import load as load_scenario

    return load_scenario(path, include_dirs)


def mjcf_text(scene: dict[str, Any]) -> str:
    """The MJCF text `prsc compile --target mjcf` writes for a scene (meshes at ../assets/, as in its output)."""
    from prsc.scenario import mjcf_text as text

    return text(scene)


def mujoco_spec(scene: dict[str, Any]) -> mujoco.MjSpec:
    """The scene's MjSpec, parsed from `mjcf_text` with its meshes given in memory (prsc.scenario)."""
    from prsc.scenario import mujoco_spec as spec

    return spec(scene)


def mujoco_model(scene: dict[str, Any]) -> mujoco.MjModel:
    """A `mujoco.MjModel` of a scene, built in memory: the model of the file `prsc compile` writes."""
    from prsc.scenario import mujoco_model as model

    return model(scene)


def __getattr__(name: str) -> Any:
    """`prsc.SceneEnv` and `prsc.RecordEpisodes`, imported on first use (they need the [gym] extra)."""
    if name == "SceneEnv":
        from prsc.scene_env import SceneEnv

        return SceneEnv
    if name == "RecordEpisodes":
        from prsc.record_episodes import RecordEpisodes

        return RecordEpisodes
    raise AttributeError(f"module 'prsc' has no attribute {name!r}")
