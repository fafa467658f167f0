"""20 scenes of every spec: pybullet.loadSDF loads the SDF world with the scene's poses, and
`ign sdf -k` accepts the first scenes of each spec."""

from __future__ import annotations

import shutil

import pytest

from tests.backends import readback
from tests.backends.specs import all_specs, compiled, spec_id

SPECS = all_specs()
IGN_SCENES = 3  # `ign` costs 1-2 s a file (mostly a Ruby start-up)


@pytest.fixture(scope="module", params=SPECS, ids=[spec_id(s) for s in SPECS])
def spec_output(request, tmp_path_factory):
    return compiled(tmp_path_factory.mktemp("specs_sdf"), request.param, ["sdf"])


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
