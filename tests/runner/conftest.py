"""Fixtures for the runner tests: the hand-made Table-Cube scene and variants of it."""

from __future__ import annotations

import copy
import json
import os
from pathlib import Path

import textwrap

import pytest

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("PYOPENGL_PLATFORM", os.environ["MUJOCO_GL"])

DATA = Path(__file__).resolve().parents[1] / "data"


def _object(scene: dict, name: str) -> dict:
    return next(o for o in scene["objects"] if o["name"] == name)


@pytest.fixture
def table_cube() -> dict:
    """A fresh copy of tests/data/table_cube_scene.json (cube c1 on tray tr_1, camera overhead)."""
    return json.loads((DATA / "table_cube_scene.json").read_text())


@pytest.fixture
def compile_scene(tmp_path):
    """Compile a scene dict to MJCF as `prsc compile --target mjcf` does; returns the file path."""
    from prsc.commands.compile import compile_scenes

    def compile_(scene: dict, name: str = "scene") -> Path:
        source = tmp_path / f"{name}.json"
        source.write_text(json.dumps(scene))
        root = compile_scenes(str(source), ["mjcf"], 1, 0, str(tmp_path / "compiled"))
        return root / "mjcf" / "00000.xml"

    return compile_


@pytest.fixture
def variant():
    """`variant(scene, name=(x, y), ...)`: a copy of a scene with objects moved horizontally."""

    def variant_(scene: dict, **moves: tuple[float, float]) -> dict:
        out = copy.deepcopy(scene)
        for name, (x, y) in moves.items():
            _object(out, name)["position"][:2] = [x, y]
        return out

    return variant_


# The controller a user writes: three cubes on a table must stay put for a simulated second.
STAY_PUT = textwrap.dedent('''
    import mujoco
    import numpy as np


    class StayPut:
        outcomes = ("still", "moved")

        def __call__(self, scene, model, data):
            names = [o["name"] for o in scene["objects"] if o["class"] == "Cube"]
            ids = [model.body(name).id for name in names]
            start = data.xpos[ids].copy()
            while data.time < 1.0:
                mujoco.mj_step(model, data)
            drift = np.linalg.norm(data.xpos[ids] - start, axis=1)
            worst = int(np.argmax(drift))
            moved = drift[worst] > 0.005
            reason = f"{names[worst]} moved {drift[worst] * 1000:.1f} mm" if moved else ""
            return {"outcome": "moved" if moved else "still", "reason": reason,
                    "drift_mm": [round(float(d) * 1000, 3) for d in drift]}


    stay_put = StayPut()
''')



@pytest.fixture
def stay_put(tmp_path) -> str:
    """`--controller` target of STAY_PUT written to a temporary file."""
    path = tmp_path / "stay_put.py"
    path.write_text(STAY_PUT)
    return f"{path}:stay_put"
