"""Convex decomposition of a concave mesh (CoACD), built once and cached in the build folder.

Every simulator collides a mesh as its convex hull, so a cup's hull fills its opening. A
mesh with `collision "decomposed"` collides as the union of convex pieces instead
(docs/backends.md, "Mesh collision"). CoACD takes seconds to a minute per mesh, so pieces
are cached under `$PRSC_BUILD_DIR/assets/convex/` keyed by the mesh's bytes, the CoACD
version and its settings: later compiles, scenes and workers reuse them.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from prsc.errors import PrscError
from prsc.files import atomic_write_tree
from prsc.user_assets.asset_files import build_root
from prsc.user_assets.mesh_paths import load_mesh, obj_text

SETTINGS = {"threshold": 0.05, "preprocess_mode": "auto", "max_convex_hull": -1, "seed": 0}
"""CoACD's own defaults (concavity threshold 0.05 of the mesh size), with a fixed seed."""


def _decompose(source: Path) -> dict[str, str]:
    """The convex pieces of the mesh at `source`: OBJ text by file name (`00.obj`, `01.obj`, ...)."""
    import coacd
    import numpy as np
    import trimesh

    loaded = load_mesh(source)
    mesh = trimesh.Trimesh(loaded.vertices, loaded.faces)  # geometry only: UV seams merged into one solid
    coacd.set_log_level("error")
    pieces = coacd.run_coacd(coacd.Mesh(np.asarray(mesh.vertices), np.asarray(mesh.faces)), **SETTINGS)
    if not pieces:
        raise PrscError(f"the convex decomposition of mesh {source.name} found no pieces")
    files = {}
    for k, (vertices, faces) in enumerate(pieces):
        # Each piece as its own convex hull: consistent outward faces for every simulator.
        hull = trimesh.Trimesh(np.asarray(vertices), np.asarray(faces)).convex_hull
        files[f"{k:02d}.obj"] = obj_text(hull.vertices, hull.faces)
    return files


def convex_pieces(source: Path) -> tuple[Path, ...]:
    """The convex pieces (OBJ files, in the mesh's own frame) of the mesh at `source`."""
    from importlib.metadata import version

    digest = hashlib.sha256(repr((version("coacd"), sorted(SETTINGS.items()))).encode())
    digest.update(Path(source).read_bytes())
    target = build_root() / "assets" / "convex" / f"{Path(source).stem}-{digest.hexdigest()[:12]}"
    if not target.is_dir():
        files = _decompose(Path(source))
        if not target.is_dir():  # another worker may have finished first: keep its set
            target.parent.mkdir(parents=True, exist_ok=True)
            # The whole set is renamed into place at once: a reader never sees half of it.
            atomic_write_tree(target, files)
    return tuple(sorted(target.glob("*.obj")))
