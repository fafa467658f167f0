"""A worker's render context, kept from one scene to the next, renders the bits a fresh one does."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from prsc.runner import rendering
from prsc.runner.harness import fresh_data, load_model
from prsc.cli import main

REPO = Path(__file__).resolve().parents[2]


def _images(model: mujoco.MjModel, camera: int) -> tuple[np.ndarray, np.ndarray]:
    data = fresh_data(model)
    mujoco.mj_step(model, data, nstep=50)
    renderer = rendering.OffscreenRenderer(model, 320, 240)
    try:
        return renderer.rgb(data, camera), renderer.depth(data, camera)
    finally:
        renderer.close()


def test_a_kept_render_context_renders_what_a_fresh_one_does(tmp_path):
    assert main(["compile", str(REPO / "specs" / "table_cube.prs"), "--target", "json,mjcf", "-n", "3",
                 "-o", str(tmp_path)]) == 0
    models = [load_model(tmp_path / "table_cube" / "mjcf" / f"0000{k}.xml") for k in range(3)]
    assert len({rendering._render_key(m) for m in models}) == 1  # one context serves every scene of the spec
    camera = mujoco.mj_name2id(models[0], mujoco.mjtObj.mjOBJ_CAMERA, "camera")
    counts = rendering.context_counts()
    kept = [_images(m, camera) for m in models]  # scene 0's context, reused for 1 and 2
    made, patched = (rendering.context_counts()[k] - counts[k] for k in ("contexts made", "contexts patched"))
    assert made <= 1 and patched == 2  # three extents, one context
    for model, (rgb, depth) in zip(models, kept):
        rendering._kept = None  # the next context is made fresh for this model
        fresh_rgb, fresh_depth = _images(model, camera)
        assert np.array_equal(rgb, fresh_rgb) and np.array_equal(depth, fresh_depth)
    assert kept[0][0].std() > 10 and not np.array_equal(kept[0][0], kept[1][0])  # real, different images
