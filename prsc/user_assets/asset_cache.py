"""Cache entries built from the user's asset files (docs/assets.md, "Caches"): keyed by the
content of every file they read, holding copies of those files, never a path to them.

An asset file reads others: a URDF its meshes, an MJCF its included files, meshes, textures
and height fields, an OBJ its material files and their images. What prsc builds from it in
the build folder (the URDF every format converts, scaled copies, reach rings) is named by
`inputs_digest`, a hash of all of them and of where they sit relative to the asset file,
so an edited mesh under an unchanged URDF gets a new entry, and the same robot in another
folder finds its entry (Bazel's content-addressed caches). An entry is a folder: its main
file names copies of what it reads by relative paths (`files/<hash>/<name>`), so it still
loads when the folder it was first built from is gone, or the build folder has moved. An
entry that names a file it lacks (an older prsc's, or one partly deleted) is rebuilt.

Foundation module (user_assets): it imports no mujoco.
"""

from __future__ import annotations

import hashlib
import os
import xml.etree.ElementTree as ET
from functools import lru_cache
from pathlib import Path
from typing import Sequence

from prsc.errors import read_error
from prsc.files import atomic_write
from prsc.user_assets.mesh_paths import obj_material_files
from prsc.user_assets.urdf_source import mesh_file, parse_urdf

INPUTS_VERSION = "1"  # bump when what `inputs_digest` hashes changes
FILES = "files"  # an entry's copies of what it reads: files/<hash>/<name>

_MJCF_FILE_ATTRIBUTES = {  # MJCF elements naming files, and the compiler folder each is relative to
    "mesh": ("meshdir", ("file",)),
    "skin": ("meshdir", ("file",)),
    "hfield": ("assetdir", ("file",)),
    "texture": ("texturedir", ("file", "fileright", "fileleft", "fileup", "filedown", "filefront", "fileback")),
}


def read_input(path: Path | str) -> bytes:
    """The bytes of a file an asset reads, or `cannot read PATH: reason` (never an output's name)."""
    try:
        return Path(path).read_bytes()
    except OSError as error:
        raise read_error(error, path) from None


def asset_inputs(path: Path | str, folders: Sequence[str] = ()) -> tuple[Path, ...]:
    """Every file an asset file reads: itself, then each mesh, texture and included file it
    names and an OBJ's material files and their images, each once, in the order named."""
    path = Path(path).resolve()
    try:
        stat = os.stat(path)
    except OSError as error:
        raise read_error(error, path) from None
    return _inputs(str(path), stat.st_mtime_ns, stat.st_size, tuple(folders))


@lru_cache(maxsize=64)
def _inputs(source: str, mtime_ns: int, size: int, folders: tuple[str, ...]) -> tuple[Path, ...]:
    path = Path(source)
    named = _urdf_files(path, folders) if path.suffix.lower() == ".urdf" else _mjcf_files(path, path, set())
    found: dict[Path, None] = {path: None}
    for file in named:
        found.setdefault(file, None)
        for companion in obj_material_files(file) if file.is_file() else ():
            found.setdefault(companion.resolve(), None)
    return tuple(found)


def _urdf_files(path: Path, folders: Sequence[str]) -> list[Path]:
    return [Path(mesh_file(mesh.get("filename", ""), path, folders)) for mesh in parse_urdf(path).iter("mesh")]


def _mjcf_files(path: Path, main: Path, seen: set[Path]) -> list[Path]:
    """The files an MJCF (and the files it includes, relative to the main file) names."""
    if path in seen:
        return []
    seen.add(path)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError):
        return []  # MuJoCo's own load says what is wrong with it
    folders = {"meshdir": "", "texturedir": "", "assetdir": ""}
    for compiler in root.iter("compiler"):
        assetdir = compiler.get("assetdir")
        for key in folders:
            folders[key] = compiler.get(key) or assetdir or folders[key]
    files: list[Path] = []
    for element in root.iter():
        if element.tag == "include" and element.get("file"):
            included = (main.parent / element.get("file")).resolve()
            files.append(included)
            files.extend(_mjcf_files(included, main, seen))
        elif element.tag in _MJCF_FILE_ATTRIBUTES:
            folder, attributes = _MJCF_FILE_ATTRIBUTES[element.tag]
            for attribute in attributes:
                if element.get(attribute):
                    files.append((main.parent / folders[folder] / element.get(attribute)).resolve())
    return files


def input_stats(path: Path | str, folders: Sequence[str] = ()) -> tuple[tuple[str, int, int], ...]:
    """(path, mtime_ns, size) of every file the asset reads (-1s for one that is missing):
    the key of per-process caches, which then see an edited mesh too."""
    stats = []
    for file in asset_inputs(path, folders):
        try:
            stat = os.stat(file)
            stats.append((str(file), stat.st_mtime_ns, stat.st_size))
        except FileNotFoundError:
            stats.append((str(file), -1, -1))
        except OSError as error:
            raise read_error(error, file) from None
    return tuple(stats)


def inputs_digest(path: Path | str, folders: Sequence[str] = ()) -> str:
    """sha256 of every file the asset reads, each with its path relative to the asset file:
    the key of everything built from it (equal files in another folder, equal key)."""
    return _digest(input_stats(path, folders))


@lru_cache(maxsize=256)
def _digest(stats: tuple[tuple[str, int, int], ...]) -> str:
    base = Path(stats[0][0]).parent
    digest = hashlib.sha256(f"prsc asset inputs {INPUTS_VERSION}\0".encode())
    for name, _, size in stats:
        digest.update(os.path.relpath(name, base).encode() + b"\0")
        digest.update(b"missing" if size < 0 else hashlib.sha256(read_input(name)).digest())
    return digest.hexdigest()


# ------------------------------------------------------------------ entries

def bundle_copy(source: Path | str, folder: Path) -> str:
    """A copy of `source` (an OBJ with its material files and their images beside it, as they
    sit) inside the cache entry `folder`; returns its path relative to `folder`."""
    source = Path(source)
    companions = [c for c in obj_material_files(source) if c.is_file()]
    placed = [(c, os.path.relpath(c, source.parent)) for c in companions]
    placed = [(c, rel) for c, rel in placed if not rel.startswith("..")]  # kept only where they sit below the mesh
    data = read_input(source)
    digest = hashlib.sha256(data)
    contents = []
    for companion, rel in placed:
        content = read_input(companion)
        digest.update(rel.encode() + b"\0" + hashlib.sha256(content).digest())
        contents.append((rel, content))
    target = folder / FILES / digest.hexdigest()[:16] / source.name
    for rel, content in contents:  # a copy deleted from the cache is copied again
        if not (target.parent / rel).is_file():
            (target.parent / rel).parent.mkdir(parents=True, exist_ok=True)
            atomic_write(target.parent / rel, content)
    if not target.is_file():
        target.parent.mkdir(parents=True, exist_ok=True)
        atomic_write(target, data)
    return target.relative_to(folder).as_posix()


def bundle_urdf(root: ET.Element, folder: Path) -> ET.Element:
    """A URDF tree (mesh paths absolute) with every mesh a copy inside the entry `folder`."""
    for mesh in root.iter("mesh"):
        mesh.set("filename", bundle_copy(mesh.get("filename", ""), folder))
    return root


def bundle_mjcf(root: ET.Element, folder: Path) -> ET.Element:
    """An MJCF tree (asset paths absolute, no meshdir) with every file a copy inside `folder`."""
    for element in root.iter():
        for attribute in _MJCF_FILE_ATTRIBUTES.get(element.tag, ("", ()))[1]:
            if element.get(attribute):
                element.set(attribute, bundle_copy(element.get(attribute), folder))
    return root


def _named(root: ET.Element) -> list[str]:
    """The files a URDF or MJCF tree names."""
    names = [mesh.get("filename", "") for mesh in root.iter("mesh") if mesh.get("filename")]
    for element in root.iter():
        names += [element.get(a) for a in _MJCF_FILE_ATTRIBUTES.get(element.tag, ("", ()))[1] if element.get(a)]
    return names


def entry_usable(main: Path) -> bool:
    """Whether a cache entry can be used as it is: its main file parses and every file it names
    is inside its folder and there (else it is rebuilt, not trusted)."""
    try:
        root = ET.parse(main).getroot()
    except (OSError, ET.ParseError):
        return False
    folder = main.parent.resolve()
    for name in _named(root):
        if os.path.isabs(name) or not (folder / name).resolve().is_relative_to(folder) or not (folder / name).is_file():
            return False
    return True


def write_entry(main: Path, root: ET.Element, header: str = '<?xml version="1.0"?>\n') -> Path:
    """Write a cache entry's main file (after the copies it names, so it marks the entry complete)."""
    main.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(main, header + ET.tostring(root, encoding="unicode") + "\n")
    return main
