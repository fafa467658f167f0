"""URDFs as ROS and Drake write them. COLLADA meshes (`.dae`, as most ROS URDFs' visuals are):
prsc reads them through trimesh (pycollada) and writes OBJ copies, which MuJoCo decodes,
with the file's colour on the visual. Attributes under a prefix the file never declares
(Drake's `drake:acceleration`), which MuJoCo and pybullet ignore, are read too
(docs/assets.md)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from tests.backends import readback

RED = (0.8, 0.1, 0.1)


def _collada_box(path) -> None:
    import trimesh

    box = trimesh.creation.box((0.3, 0.2, 0.1))
    box.visual = trimesh.visual.ColorVisuals(box, face_colors=[int(255 * c) for c in RED] + [255])
    path.write_bytes(trimesh.exchange.dae.export_collada(box))


def test_a_urdf_with_collada_meshes_compiles_in_every_format_with_their_colour(tmp_path):
    import mujoco

    _collada_box(tmp_path / "block.dae")
    (tmp_path / "block.urdf").write_text(textwrap.dedent("""\
        <robot name="block">
          <link name="body">
            <inertial><mass value="0.5"/><inertia ixx="0.002" ixy="0" ixz="0" iyy="0.004" iyz="0" izz="0.005"/></inertial>
            <visual><geometry><mesh filename="block.dae"/></geometry></visual>
            <collision><geometry><mesh filename="block.dae"/></geometry></collision>
          </link>
        </robot>
        """))
    (tmp_path / "s.prs").write_text(textwrap.dedent("""\
        from tabletop import *
        class Block:
            model: "block.urdf"
        table = Table on Vector3D(0, 0, 0)
        b = Block completely on table
        """))
    done = subprocess.run([sys.executable, "-m", "prsc.cli", "compile", str(tmp_path / "s.prs"), "-n", "1",
                           "--target", "json,mjcf,urdf,sdf,usd", "-o", str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    root = tmp_path / "out" / "s"
    model = mujoco.MjModel.from_xml_path(str(root / "mjcf" / "00000.xml"))
    bodies = {b for b in range(model.nbody) if model.body(b).name in ("b", "b/body")}
    geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] in bodies and model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH]
    assert geoms, "the block has no mesh geom"
    # The collision hull is the box's (0.3 x 0.2 x 0.1 m), and the drawn mesh has the file's red.
    extent = [2 * model.mesh_vert[model.mesh_vertadr[m]:model.mesh_vertadr[m] + model.mesh_vertnum[m]].max(axis=0)
              for m in {model.geom_dataid[g] for g in geoms}]
    assert np.allclose(sorted(extent[0]), [0.1, 0.2, 0.3], atol=1e-4)
    drawn = [g for g in geoms if model.geom_contype[g] == 0 and model.geom_conaffinity[g] == 0]
    assert drawn and np.allclose(model.geom_rgba[drawn[0]][:3], RED, atol=0.01)
    readback.urdf_validate(root / "urdf" / "00000")
    assert readback.usd_errors(root / "usd" / "00000.usda") == []
    assert "b" in readback.sdf_poses(root / "sdf" / "00000.sdf")


def test_an_unreadable_collada_mesh_is_an_error_at_the_model_line(tmp_path):
    (tmp_path / "bad.dae").write_text("<COLLADA>not a mesh</COLLADA>")
    (tmp_path / "bad.urdf").write_text('<robot name="bad"><link name="l"><visual><geometry><mesh filename="bad.dae"/>'
                                      '</geometry></visual></link></robot>')
    (tmp_path / "s.prs").write_text('from tabletop import *\nclass Bad:\n    model: "bad.urdf"\nb = Bad on Vector3D(0, 0, 0)\n')
    done = subprocess.run([sys.executable, "-m", "prsc.cli", "check", str(tmp_path / "s.prs")],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "s.prs:3:" in done.stderr and "bad.dae" in done.stderr, done.stderr


def test_a_prefix_the_urdf_never_declares_is_read_as_mujoco_and_pybullet_read_it(tmp_path):
    (tmp_path / "arm.urdf").write_text(textwrap.dedent("""\
        <robot name="two">
          <link name="base"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
            <collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
          <link name="arm"><inertial><mass value="0.5"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
            <collision><origin xyz="0 0 0.15"/><geometry><box size="0.04 0.04 0.3"/></geometry></collision></link>
          <joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/><origin xyz="0 0 0.05"/>
            <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="10" velocity="1" drake:acceleration="3"/></joint>
        </robot>
        """))
    (tmp_path / "s.prs").write_text(textwrap.dedent("""\
        from tabletop import *
        class Arm:
            model: "arm.urdf"
        a = Arm on Vector3D(0, 0, 0), with joint "hinge" 0.5
        """))
    done = subprocess.run([sys.executable, "-m", "prsc.cli", "compile", str(tmp_path / "s.prs"), "-n", "1",
                           "--target", "json,mjcf,urdf", "-o", str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    readback.urdf_validate(tmp_path / "out" / "s" / "urdf" / "00000")
    _, model, data = readback.scene_at_home(tmp_path / "out" / "s", 0)
    assert data.qpos[model.joint("a/hinge").qposadr[0]] == pytest.approx(0.5)
