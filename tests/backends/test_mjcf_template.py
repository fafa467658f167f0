"""The MJCF writer fills one template per scene topology (backends/mjcf.py): a scene written
from a template another scene built is, to the byte, what it writes from a template of its
own, for every shipped spec (random sizes, meshes, cameras, robots, furniture)."""

from __future__ import annotations

from pathlib import Path

import pytest

import prsc.backends.mjcf as mjcf
from prsc.backends.scene import parse_scene
from prsc.backends.store import AssetStore
from prsc.sampling import compile_sampler

REPO = Path(__file__).resolve().parents[2]
SPECS = sorted((REPO / "specs").glob("*.prs")) + [REPO / "specs" / "furniture" / "drawer_cubes.prs"]
SCENES = 4


@pytest.mark.parametrize("spec", SPECS, ids=lambda p: p.stem)
def test_a_shared_template_writes_what_a_scene_own_template_writes(spec, tmp_path):
    sampler = compile_sampler(spec, law="sequential")
    store, path = AssetStore(tmp_path / "assets"), tmp_path / "mjcf" / "scene.xml"
    mjcf._templates.clear()
    shared = [mjcf.mjcf_xml(parse_scene(sampler.scene(3, k)), path, store) for k in range(SCENES)]
    assert len(mjcf._templates) >= 1
    for k in range(SCENES):
        mjcf._templates.clear()
        assert mjcf.mjcf_xml(parse_scene(sampler.scene(3, k)), path, store) == shared[k], k
    assert len(set(shared)) == SCENES  # the scenes differ, so the slots were filled
