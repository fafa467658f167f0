"""Where a `with mesh "path"` file is found: the spec's folder, the --include folders, then
prsc's model library (the repository's specs/, as for imports), and nowhere else.

A path that is absolute or climbs out of those folders with `..` is read only when the
user says so (`--meshes-anywhere`): a spec from elsewhere cannot make prsc copy any
readable file into its outputs.
"""

from __future__ import annotations

import os
from functools import lru_cache
from pathlib import Path
from typing import Sequence

from prsc.errors import PrscError

MESH_COLLISIONS = ("hull", "decomposed")
"""A mesh object's `collision`: its convex hull (every simulator's default), or the convex
pieces of a CoACD decomposition (docs/backends.md, "Mesh collision")."""


def _inside(path: str, folder: str) -> bool:
    """Whether `path` lies lexically inside `folder` (no `..` escape)."""
    folder = os.path.normpath(os.path.abspath(folder))
    return os.path.normpath(os.path.abspath(path)).startswith(folder.rstrip(os.sep) + os.sep)


LIBRARY = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "specs")
"""prsc's model library (specs/ beside the package), searched last, as for imports."""


def mesh_folders(spec: str, include_dirs: Sequence[str] = ()) -> tuple[str, ...]:
    """The folders meshes of `spec` are looked up in, in order."""
    return (os.path.dirname(os.path.abspath(spec)), *include_dirs, LIBRARY)


def resolve_mesh(raw: str, folders: Sequence[str], anywhere: bool = False) -> Path:
    """The mesh file `raw` names, or a PrscError saying why it cannot be used."""
    if not raw or "\0" in raw:
        raise PrscError(f"mesh path {raw!r} is not a file name")
    if os.path.isabs(raw):
        candidates = [raw]
    else:
        candidates = [os.path.join(folder, raw) for folder in folders]
    for candidate in candidates:
        if not os.path.isfile(candidate):
            continue
        if not anywhere and not any(_inside(candidate, folder) for folder in folders):
            raise PrscError(f"mesh file {raw!r} is outside the spec's folder and the --include folders; "
                            "pass --meshes-anywhere to read it")
        return Path(candidate).resolve()
    if os.path.isabs(raw):
        raise PrscError(f"mesh file {raw!r} not found")
    spec_folder, *included = distinct_folders(folders)
    searched = [f"the spec's folder {spec_folder}"]
    library = os.path.normpath(LIBRARY)
    if library in included:
        included.remove(library)
    if included:
        searched.append(f"the --include folder{'s' * (len(included) > 1)} {', '.join(included)}")
    if library != spec_folder:
        searched.append(f"the model library {library}")
    where = ", ".join(searched[:-1]) + " or " + searched[-1] if len(searched) > 1 else searched[0]
    raise PrscError(f"mesh file {raw!r} not found in {where}")


def distinct_folders(folders: Sequence[str]) -> tuple[str, ...]:
    """`folders` as absolute paths, each once, in order (`-I .` beside the spec adds nothing)."""
    return tuple(dict.fromkeys(os.path.normpath(os.path.abspath(folder)) for folder in folders))


def mesh_extent(path: Path | str) -> tuple[float, float, float]:
    """The extent (x, y, z) of a mesh file's bounding box, in the file's units."""
    stat = os.stat(path)
    return _mesh_extent(str(path), stat.st_mtime_ns, stat.st_size)


@lru_cache(maxsize=256)
def _mesh_extent(path: str, mtime_ns: int, size: int) -> tuple[float, float, float]:
    """Bounds of a mesh file (cached while the file is unchanged)."""
    low, high = load_mesh(path).bounds
    return tuple(float(v) for v in high - low)  # type: ignore[return-value]


def obj_text(vertices, faces, comments: Sequence[str] = ()) -> str:
    """A triangle mesh as OBJ text (vertices with full precision, 1-based faces)."""
    lines = [f"# {c}" for c in comments] + [f"v {x!r} {y!r} {z!r}" for x, y, z in vertices.tolist()]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces.tolist()]
    return "\n".join(lines) + "\n"


def load_mesh(path: Path | str):
    """The triangles of a mesh file as a trimesh.Trimesh, or a PrscError saying why not."""
    import trimesh

    try:
        mesh = trimesh.load(path, force="mesh")
    except Exception:  # trimesh raises many types for unreadable files
        # Its message may quote the file (a token of a text file): say only what failed.
        raise PrscError(f"cannot read mesh {path}: not a mesh file trimesh can load "
                        "(STL, OBJ, PLY, OFF, GLB/GLTF, ...)") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise PrscError(f"mesh {path} holds no triangles")
    return mesh
