"""Where a `with mesh "path"` file is found: the spec's folder and the --include folders only.

A path that is absolute or climbs out of those folders with `..` is read only when the
user says so (`--meshes-anywhere`): a spec from elsewhere cannot make prsc copy any
readable file into its outputs.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Sequence

from prsc.errors import PrscError


def _inside(path: str, folder: str) -> bool:
    """Whether `path` lies lexically inside `folder` (no `..` escape)."""
    folder = os.path.normpath(os.path.abspath(folder))
    return os.path.normpath(os.path.abspath(path)).startswith(folder.rstrip(os.sep) + os.sep)


def mesh_folders(spec: str, include_dirs: Sequence[str] = ()) -> tuple[str, ...]:
    """The folders meshes of `spec` are looked up in, in order."""
    return (os.path.dirname(os.path.abspath(spec)), *include_dirs)


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
    looked = ", ".join(candidates)
    raise PrscError(f"mesh file {raw!r} not found (looked for {looked})")
