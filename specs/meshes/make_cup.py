"""Writes cup.obj beside this file: the example's "user mesh" (specs/user_mesh.prs).

A cup as a CAD tool would export it: millimetres, origin at the centre of its base, z up.
80 mm across, 95 mm tall, 5 mm walls and an 8 mm base, turned about z from its profile.
Run `.venv/bin/python specs/meshes/make_cup.py` to write it again (the same bytes).
"""

from pathlib import Path

import numpy as np
import trimesh

RADIUS, HEIGHT, WALL, BASE = 40.0, 95.0, 5.0, 8.0  # mm
SECTIONS = 24

# (radius, z) of the cup's outline, outside first, then down the inside.
profile = np.array([[0, 0], [RADIUS, 0], [RADIUS, HEIGHT], [RADIUS - WALL, HEIGHT],
                    [RADIUS - WALL, BASE], [0, BASE]])
cup = trimesh.creation.revolve(profile, sections=SECTIONS)
assert cup.is_volume
lines = ["# cup, millimetres, written by make_cup.py"]
lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in cup.vertices.tolist()]
lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in cup.faces.tolist()]
(Path(__file__).parent / "cup.obj").write_text("\n".join(lines) + "\n")
