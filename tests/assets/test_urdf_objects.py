"""A URDF of one link and no joints is a rigid free object (docs/assets.md): pybullet's
random_urdfs blobs (whose inertia no simulator accepts: prsc takes it from the geometry,
and says so) and its tray, sized by their collision meshes, placed on a table, compiled
to every format; in MuJoCo they come to rest, and pybullet loads them as free bodies."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.backends import readback

pybullet_data = pytest.importorskip("pybullet_data")
DATA = Path(pybullet_data.getDataPath())

SPEC = """\
from tabletop import *
table = Table on Vector3D(0, 0, 0), with width 1.2, with length 0.8, with height 0.75
class Blob:
    model: "random_urdfs/000/000.urdf"
class Blob7:
    model: "random_urdfs/007/007.urdf"
class UrdfTray:
    model: "tray/tray.urdf"
t = UrdfTray completely on table
a = Blob completely on table
b = Blob7 completely on table
"""


def test_one_link_urdfs_are_free_objects_in_every_format(tmp_path):
    spec = tmp_path / "objects.prs"
    spec.write_text(SPEC)
    done = subprocess.run([sys.executable, "-m", "prsc.cli", "compile", str(spec), "-I", str(DATA), "-n", "3",
                           "--target", "json,mjcf,urdf,sdf,usd", "-o", str(tmp_path / "out"), "--settle-check"],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "3 of 3 scenes at rest" in done.stdout
    assert "000.urdf: links random_obj_000 have a mass or inertia no simulator accepts" in done.stderr
    root = tmp_path / "out" / "objects"
    for k in range(3):
        scene = json.loads((root / "json" / f"{k:05d}.json").read_text())
        objects = {o["name"]: o for o in scene["objects"]}
        assert not objects["a"]["static"] and objects["t"]["dimensions"][2] < 0.2  # a tray, not its mesh's box
        poses, drops = readback.urdf_bundle_load(root / "urdf" / f"{k:05d}", visuals=False)
        readback.assert_poses(poses, scene, f"urdf scene {k}")
        readback.assert_free_fall(drops, scene, where=f"scene {k}: ")
        assert readback.usd_errors(root / "usd" / f"{k:05d}.usda") == []
