"""6 scenes of every spec, compiled once to every format (one fixture per spec, shared):

- MJCF loads, settles without jumps, and keeps the poses; every `completely on` object is at
  rest by `prsc compile --settle-check`'s test;
- USD validates with zero errors and keeps the poses;
- each URDF bundle loads in pybullet DIRECT with the poses, free objects fall under gravity
  and fixed ones stay, and yourdfpy validates every file;
- pybullet.loadSDF loads the SDF world with the poses, and `ign sdf -k` accepts each spec's first scene;
- the JSON is the sampler's scene, every scene in the manifest.
"""

from __future__ import annotations

import shutil

import pytest

from prsc.runner.settle_check import settle_scenes
from prsc.pipeline.output_folder import compiled_scenes
from tests.backends import readback
from tests.backends.test_settle_check import completely_on
from tests.backends.specs import SCENES_PER_SPEC, all_specs, compiled, spec_id

SPECS = all_specs()
IGN_SCENES = 1  # `ign` costs 0.5-1 s a file (mostly a Ruby start-up); the schema is checked on each
# spec's first scene (its other scenes have the same elements unless the spec draws a model),
# pybullet loads all of them


@pytest.fixture(scope="module", params=SPECS, ids=[spec_id(s) for s in SPECS])
def spec_output(request, tmp_path_factory):
    return compiled(tmp_path_factory.mktemp("specs"), request.param, ["mjcf", "usd", "urdf", "sdf"])


def test_mjcf_loads_settles_and_keeps_the_poses(spec_output):
    root, scenes = spec_output
    failures = []
    for k, scene in enumerate(scenes):
        model = readback.mjcf_model(root / "mjcf" / f"{k:05d}.xml")
        readback.assert_poses(readback.mjcf_poses(model, scene), scene, f"mjcf scene {k}")
        failures += [f"scene {k}: {f}" for f in readback.mjcf_settle_failures(model)]
    assert failures == []


def test_every_completely_on_object_is_at_rest(request, spec_output):
    """`prsc compile --settle-check`'s test on the same scenes (one compile serves both)."""
    spec = request.node.callspec.params["spec_output"]
    names = completely_on(spec)
    if not names:
        pytest.skip(f"{spec.name} places nothing `completely on`")
    results = settle_scenes(compiled_scenes(spec_output[0]))
    assert len(results) == SCENES_PER_SPEC
    moved = [(r.index, d.name, round(d.distance * 1000, 1), d.cause) for r in results for d in r.drifts if d.name in names]
    assert not moved, moved


def test_usd_validates_and_keeps_the_poses(spec_output):
    root, scenes = spec_output
    for k, scene in enumerate(scenes):
        path = root / "usd" / f"{k:05d}.usda"
        assert readback.usd_errors(path) == [], f"scene {k}"
        readback.assert_poses(readback.usd_poses(path, scene), scene, f"usd scene {k}")


def test_every_scene_is_in_the_manifest(spec_output):
    root, scenes = spec_output
    assert [s["index"] for s in scenes] == list(range(SCENES_PER_SPEC))


def test_urdf_bundles_load_validate_and_keep_free_objects_free(spec_output):
    root, scenes = spec_output
    for k, scene in enumerate(scenes):
        folder = root / "urdf" / f"{k:05d}"
        # Visual meshes are the same Panda files in every scene: load them in scene 0 only.
        poses, drops = readback.urdf_bundle_load(folder, visuals=(k == 0))
        readback.assert_poses(poses, scene, f"urdf scene {k}")
        readback.assert_free_fall(drops, scene, where=f"scene {k}: ")
        readback.urdf_validate(folder)


def test_sdf_loads_in_pybullet_with_the_poses(spec_output):
    root, scenes = spec_output
    for k, scene in enumerate(scenes):
        readback.assert_poses(readback.sdf_poses(root / "sdf" / f"{k:05d}.sdf"), scene, f"sdf scene {k}")


@pytest.mark.skipif(shutil.which("ign") is None, reason="ign (Debian ignition-tools + libsdformat-dev) not installed")
def test_sdf_passes_ign_sdf_check(spec_output):
    root, scenes = spec_output
    for k in range(min(IGN_SCENES, len(scenes))):
        result = readback.ign_check(root / "sdf" / f"{k:05d}.sdf")
        assert result.returncode == 0 and "Valid" in result.stdout, f"scene {k}: {result.stderr[-2000:]}"
