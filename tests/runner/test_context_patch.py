"""A render context kept when only stat.extent changed takes the numbers MuJoCo derives from it
(the shadow clip, the fog range) in place, without being made again, and renders the bits a
fresh renderer on a freshly compiled model renders: RGB and depth, with fog and a shadow.
The same renders without the patch differ, so the patch is what makes them equal."""

from __future__ import annotations

import mujoco
import numpy as np

from prsc.runner import rendering
from prsc.scene_cameras import Renderers

# A finite plane (as prsc's ground), a box, a shadow-casting spot light and fog over a short range:
# the shadow clip and the fog range both scale with stat.extent.
XML = """
<mujoco>
  <statistic extent="{extent}" center="0 0 0.3"/>
  <visual><map fogstart="0.8" fogend="2.5" shadowclip="0.5"/><global offwidth="160" offheight="120"/></visual>
  <asset>
    <texture name="grid" type="2d" builtin="checker" rgb1=".8 .8 .8" rgb2=".6 .6 .6" width="64" height="64"/>
    <material name="grid" texture="grid" texrepeat="8 8" texuniform="true"/>
  </asset>
  <worldbody>
    <light pos="0.3 -0.2 2" dir="-0.1 0.1 -1" castshadow="true" cutoff="50"/>
    <geom name="ground" type="plane" size="10 10 0.05" material="grid"/>
    <geom type="box" pos="0 0 0.2" size="0.1 0.15 0.2" rgba="0.8 0.3 0.2 1"/>
    <camera name="view" pos="0 -1.6 1.0" xyaxes="1 0 0 0 0.55 0.83"/>
  </worldbody>
</mujoco>
"""
EXTENTS = (1.0, 1.75)


def _model(extent: float) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(XML.format(extent=extent))


def _render(renderer: mujoco.Renderer, model: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray]:
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    renderer.update_scene(data, "view")
    renderer.scene.flags[mujoco.mjtRndFlag.mjRND_FOG] = True
    renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = True
    rgb = renderer.render()
    renderer.enable_depth_rendering()
    try:
        return rgb, renderer.render()
    finally:
        renderer.disable_depth_rendering()


def _fresh(extent: float) -> tuple[np.ndarray, np.ndarray]:
    model = _model(extent)
    with mujoco.Renderer(model, 120, 160) as renderer:
        return _render(renderer, model)


def test_a_change_of_extent_alone_patches_the_context_and_renders_what_a_fresh_one_does():
    model = _model(EXTENTS[0])
    renderers = Renderers(model)
    try:
        first = _render(renderers.get(120, 160), model)
        before = rendering.context_inputs(model), rendering.context_patch(model)
        model.stat.extent = EXTENTS[1]  # as `apply` sets it for another scene
        assert rendering.context_inputs(model) == before[0] and rendering.context_patch(model) != before[1]
        unpatched = _render(renderers._by_size[(120, 160)], model)  # the kept context, not yet patched
        kept = _render(renderers.get(120, 160), model)
        assert (renderers.remade, renderers.patched) == (0, 1)
        fresh = _fresh(EXTENTS[1])
        assert all(np.array_equal(a, b) for a, b in zip(kept, fresh)), "patched context differs from a fresh one"
        # The test can fail: unpatched, the shadow clip and fog of the old extent show.
        assert not np.array_equal(unpatched[0], fresh[0]) and not np.array_equal(first[0], fresh[0])
    finally:
        renderers.close()


def test_the_runner_kept_context_is_patched_not_made_again():
    models = [_model(e) for e in EXTENTS]
    data = [mujoco.MjData(m) for m in models]
    for m, d in zip(models, data):
        mujoco.mj_forward(m, d)
    images = []
    counts = rendering.context_counts()
    for model, datum in zip(models, data):
        renderer = rendering.OffscreenRenderer(model, 160, 120)
        images.append(renderer.rgb_depth(datum, 0))
        renderer.close()
    after = rendering.context_counts()
    assert after["contexts patched"] - counts["contexts patched"] == 1
    rendering._kept = None  # a fresh context for the second model
    fresh = rendering.OffscreenRenderer(models[1], 160, 120)
    expected = fresh.rgb_depth(data[1], 0)
    fresh.close()
    assert all(np.array_equal(a, b) for a, b in zip(images[1], expected))
    assert rendering.context_counts()["contexts made"] - after["contexts made"] == 1
