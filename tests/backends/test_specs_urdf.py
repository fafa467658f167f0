"""20 scenes of every spec: each URDF bundle loads in pybullet DIRECT with the scene's poses,
free objects fall under gravity and fixed ones stay, and yourdfpy validates every file."""

from __future__ import annotations

import pytest

from tests.backends import readback
from tests.backends.specs import all_specs, compiled, spec_id

SPECS = all_specs()


@pytest.fixture(scope="module", params=SPECS, ids=[spec_id(s) for s in SPECS])
def spec_output(request, tmp_path_factory):
    return compiled(tmp_path_factory.mktemp("specs_urdf"), request.param, ["urdf"])


def test_urdf_bundles_load_validate_and_keep_free_objects_free(spec_output):
    root, scenes = spec_output
    for k, scene in enumerate(scenes):
        folder = root / "urdf" / f"{k:05d}"
        # Visual meshes are the same Panda files in every scene: load them in scene 0 only.
        poses, drops = readback.urdf_bundle_load(folder, visuals=(k == 0))
        readback.assert_poses(poses, scene, f"urdf scene {k}")
        readback.assert_free_fall(drops, scene, where=f"scene {k}: ")
        readback.urdf_validate(folder)
