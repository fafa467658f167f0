"""20 scenes of every spec: the MJCF loads, settles without jumps, and poses match; the USD
validates with zero errors and its poses match; the JSON is the sampler's scene."""

from __future__ import annotations

import pytest

from tests.backends import readback
from tests.backends.specs import SCENES_PER_SPEC, all_specs, compiled, spec_id

SPECS = all_specs()


@pytest.fixture(scope="module", params=SPECS, ids=[spec_id(s) for s in SPECS])
def spec_output(request, tmp_path_factory):
    return compiled(tmp_path_factory.mktemp("specs_mj"), request.param, ["mjcf", "usd"])


def test_mjcf_loads_settles_and_keeps_the_poses(spec_output):
    root, scenes = spec_output
    failures = []
    for k, scene in enumerate(scenes):
        model = readback.mjcf_model(root / "mjcf" / f"{k:05d}.xml")
        readback.assert_poses(readback.mjcf_poses(model, scene), scene, f"mjcf scene {k}")
        failures += [f"scene {k}: {f}" for f in readback.mjcf_settle_failures(model)]
    assert failures == []


def test_usd_validates_and_keeps_the_poses(spec_output):
    root, scenes = spec_output
    for k, scene in enumerate(scenes):
        path = root / "usd" / f"{k:05d}.usda"
        assert readback.usd_errors(path) == [], f"scene {k}"
        readback.assert_poses(readback.usd_poses(path, scene), scene, f"usd scene {k}")


def test_every_scene_is_in_the_manifest(spec_output):
    root, scenes = spec_output
    assert [s["index"] for s in scenes] == list(range(SCENES_PER_SPEC))
