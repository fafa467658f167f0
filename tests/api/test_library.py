"""The library API: `prsc.load`, `scenario.scene(seed, index)`, `prsc.mujoco_model(scene)` without files."""

from __future__ import annotations

import re
from pathlib import Path

import mujoco
import numpy as np

import prsc
from prsc.cli import main

REPO = Path(__file__).resolve().parents[2]
SPEC = REPO / "specs" / "table_cube.prs"


def test_the_in_memory_model_is_the_model_of_the_compiled_file(tmp_path):
    scene = prsc.load(SPEC).scene(seed=4, index=2)
    assert main(["compile", str(SPEC), "--target", "mjcf", "-n", "3", "--seed", "4", "-o", str(tmp_path)]) == 0
    written = tmp_path / "table_cube" / "mjcf" / "00002.xml"
    assert prsc.mjcf_text(scene) == written.read_text()
    spec = prsc.mujoco_spec(scene)
    assert spec.to_xml() == mujoco.MjSpec.from_file(str(written)).to_xml()  # saving the spec gives the file's XML
    in_memory, from_file = prsc.mujoco_model(scene), mujoco.MjModel.from_xml_path(str(written))
    arrays = [n for n in dir(from_file) if not n.startswith("_") and "path" not in n
              and isinstance(getattr(from_file, n), np.ndarray)]
    assert len(arrays) > 100
    assert [n for n in arrays if not np.array_equal(getattr(in_memory, n), getattr(from_file, n))] == []
    data = mujoco.MjData(in_memory)
    mujoco.mj_step(in_memory, data, nstep=10)
    assert np.all(np.isfinite(data.qpos))


def test_the_library_guide_example_runs_as_written(monkeypatch):
    guide = (REPO / "docs" / "library.md").read_text()  # the README's own example: tests/docs/test_readme.py
    code = re.search(r"# The library API\n.*?```python\n(.*?)```", guide, re.S).group(1)
    assert len(code.strip().splitlines()) <= 12
    monkeypatch.chdir(REPO)
    namespace: dict = {}
    exec(compile(code, "docs/library.md", "exec"), namespace)
    assert isinstance(namespace["model"], mujoco.MjModel)
