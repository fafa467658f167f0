"""The asset store of an output folder: meshes and robot models that scene files share.

Scene files refer into the store by relative paths, so a compiled dataset folder can be
moved or copied elsewhere and still load. Every store file is written atomically and is
a pure function of its inputs, so concurrent workers may create the same file safely.
"""

from __future__ import annotations

import hashlib
import os
from functools import lru_cache
from pathlib import Path
from typing import Sequence

from prsc.assets.articulated import RobotModel
from prsc.files import atomic_copy, atomic_write, is_temporary_name
from prsc.errors import PrscError, read_error
from prsc.user_assets.mesh_paths import load_mesh, obj_text


def relative_path(target: Path | str, start: Path | str) -> str:
    """`target` relative to the folder `start`, with forward slashes."""
    return Path(os.path.relpath(Path(target), Path(start))).as_posix()


def _sha12(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()[:12]


def _files(folder: str) -> list[os.DirEntry]:
    """The files of `folder` by name, without the temporaries of a write under way."""
    return [e for e in sorted(os.scandir(folder), key=lambda e: e.name) if e.is_file() and not is_temporary_name(e.name)]


@lru_cache(maxsize=64)
def _folder_key(folder: str) -> str:
    """`<folder name>-<hash of its files' names and contents>`: equal folders, equal keys.

    Another process's half-written temporaries are not the folder's files: counted, they would
    give a process that hashed a robot's meshes while another was writing them a key of its
    own for the whole session (the key is cached), so its scenes would name other mesh folders
    than a fresh process's (the likely cause of one CI failure in test_ray, 2026-11-26)."""
    from prsc.user_assets.asset_cache import read_input

    digest = hashlib.sha256()
    try:
        entries = _files(folder)
    except OSError as error:  # an input: named as one, never as the output being written
        raise read_error(error, folder) from None
    for entry in entries:
        digest.update(entry.name.encode() + b"\0")
        digest.update(hashlib.sha256(read_input(entry.path)).digest())
    return f"{Path(folder).name}-{digest.hexdigest()[:10]}"


class AssetStore:
    """Shared files of one output folder: `<root>/<robot>/meshes/...`, `<root>/meshes/...`."""

    def __init__(self, root: Path | str, mesh_dirs: Sequence[str] = (), meshes_anywhere: bool = False):
        self.root = Path(root)
        self.mesh_dirs = tuple(mesh_dirs)  # --include folders, searched for meshes after the spec's folder
        self.meshes_anywhere = meshes_anywhere  # --meshes-anywhere: absolute and `..` mesh paths allowed

    # ------------------------------------------------------------------ robots
    def robot_file(self, robot: str, source: str | Path) -> Path:
        """The store's copy of a file robot `robot` (its RobotModel.key) uses, copied on first use.

        The whole folder is copied, so an OBJ keeps its material and texture files.
        """
        if not os.path.isfile(source):
            raise PrscError(f"cannot read {source}: {'not a file' if os.path.exists(source) else 'No such file'}")
        folder = os.path.dirname(os.path.abspath(source))
        target = self.root / robot / _folder_key(folder)
        marker = target / ".complete"
        if not marker.is_file():
            target.mkdir(parents=True, exist_ok=True)
            for entry in _files(folder):
                atomic_copy(Path(entry.path), target / entry.name)
            atomic_write(marker, "")
        return target / os.path.basename(source)

    def robot_usd(self, robot: RobotModel) -> Path:
        """The robot as a USD articulation asset (converted once, cached in the build folder).

        Its folder name carries the conversion's hash, so a changed robot never reuses a
        stale copy."""
        source = _robot_usd_source(robot)
        target = self.root / robot.key / source.parent.name / source.name
        if not target.is_file():
            target.parent.mkdir(parents=True, exist_ok=True)
            atomic_copy(source, target)
        return target

    # ------------------------------------------------------------------ meshes
    def normalised_mesh(self, source: Path, up_axis: str = "+z") -> Path:
        """An OBJ of `source` turned so `up_axis` points up, centred on its bounding box and
        scaled to a unit cube. A textured mesh keeps its UVs, and its base-colour image is
        written beside the OBJ as `<stem>.png` (with `<stem>.mtl` naming it)."""
        try:
            stat = os.stat(source)
            name = _normalised_name(str(source), stat.st_mtime_ns, stat.st_size, up_axis)
        except OSError as error:
            raise PrscError(f"cannot read mesh {source}: {error.strerror or error}") from None
        target = self.root / "meshes" / name
        if not target.is_file():
            target.parent.mkdir(parents=True, exist_ok=True)
            obj, image, maps = _normalise_mesh_obj(Path(source), up_axis, target.stem)
            if image is not None:  # the OBJ is the cache's marker, so it is written last
                atomic_write(target.with_suffix(".png"), image)
                mtl = f"newmtl texture\nKd 1 1 1\nmap_Kd {target.stem}.png\n"
                for role, png in maps.items():
                    atomic_write(_map_path(target, role), png)
                mtl += "".join(_MTL_LINES[role].format(_map_path(target, role).name) for role in maps)
                atomic_write(target.with_suffix(".mtl"), mtl)
            atomic_write(target, obj)
        return target

    def texture_image(self, source: Path) -> Path:
        """The store's PNG copy of an image `with texture` names (`textures/<stem>-<hash>.png`)."""
        import io

        from prsc.user_assets.mesh_paths import read_image

        try:
            stat = os.stat(source)
        except OSError as error:
            raise PrscError(f"cannot read image {source}: {error.strerror or error}") from None
        target = self.root / "textures" / _image_name(str(source), stat.st_mtime_ns, stat.st_size)
        if not target.is_file():
            png = io.BytesIO()
            read_image(source).save(png, format="PNG")
            target.parent.mkdir(parents=True, exist_ok=True)
            atomic_write(target, png.getvalue())
        return target

    def convex_pieces(self, normalised: Path) -> tuple[Path, ...]:
        """The store's copies of the convex pieces of a normalised mesh (decomposed once, cached)."""
        from prsc.assets.convex_pieces import convex_pieces

        pieces = convex_pieces(normalised)
        target = self.root / "meshes" / "convex" / pieces[0].parent.name
        copies = tuple(target / piece.name for piece in pieces)
        if not all(copy.is_file() for copy in copies):
            target.mkdir(parents=True, exist_ok=True)
            for piece, copy in zip(pieces, copies):
                atomic_copy(piece, copy)
        return copies


@lru_cache(maxsize=8)
def _robot_usd_source(robot: RobotModel) -> Path:
    from prsc.assets.robot_usd import robot_usd_cached

    return robot_usd_cached(robot.prim_name, robot.urdf, robot.home(), drives=not robot.passive)


@lru_cache(maxsize=256)
def _image_name(source: str, mtime_ns: int, size: int) -> str:
    """`<stem>-<hash of the file's bytes>.png` (cached while the file is unchanged: every scene asks)."""
    return f"{Path(source).stem}-{_sha12(Path(source).read_bytes())}.png"


# The OBJ/MTL PBR extension's names: a normal map, and roughness and metallic read from the
# glTF image's G and B channels.
_MTL_LINES = {"normal": "norm {0}\n", "orm": "map_Pr -imfchan g {0}\nmap_Pm -imfchan b {0}\n"}


def _map_path(normalised: Path, role: str) -> Path:
    return normalised.with_name(f"{normalised.stem}_{role}.png")


@lru_cache(maxsize=256)
def pbr_maps(texture: str | None) -> tuple[tuple[str, str], ...]:
    """(role, path) of the PBR maps the store wrote beside a mesh's base-colour image, in
    PBR_MAPS order (none for a `with texture` image or an untextured part). Cached: every
    scene asks, and the maps are written before the mesh's OBJ, whose content-hashed name
    the image's carries, so a name once seen never gains or loses a map."""
    from prsc.user_assets.mesh_paths import PBR_MAPS

    if texture is None:
        return ()
    paths = ((role, _map_path(Path(texture), role)) for role in PBR_MAPS)
    return tuple((role, str(path)) for role, path in paths if path.is_file())


def texture_of(normalised: Path | str) -> Path | None:
    """The base-colour image the store wrote beside a normalised OBJ, if the mesh is textured."""
    image = Path(normalised).with_suffix(".png")
    return image if image.is_file() else None


@lru_cache(maxsize=256)
def _normalised_name(source: str, mtime_ns: int, size: int, up_axis: str) -> str:
    """`<stem>-<hash of the file's bytes and the up axis>.obj` (cached while the file is unchanged)."""
    # v2: textured meshes keep their UVs and image; v3: and their normal and ORM maps
    key = Path(source).read_bytes() + (b"" if up_axis == "+z" else f"\0up{up_axis}".encode()) + b"\0v3"
    return f"{Path(source).stem}-{_sha12(key)}.obj"


def _normalise_mesh_obj(source: Path, up_axis: str, stem: str) -> tuple[bytes, bytes | None, dict[str, bytes]]:
    """(OBJ text of a mesh turned upright, moved to its bounding-box centre and scaled per axis
    to size 1; its base-colour image as PNG bytes, or None when it has none; its PBR maps as
    PNG bytes by role)."""
    import io

    import numpy as np

    from prsc.user_assets.mesh_paths import base_color_image, pbr_images

    mesh = load_mesh(source, up_axis)
    low, high = mesh.bounds
    extent = high - low
    if np.any(extent <= 0):
        raise PrscError(f"mesh {source} is flat (bounding box {extent.tolist()}); it cannot fill a box")
    vertices = (mesh.vertices - (low + high) / 2) / extent
    comments = ("prsc: normalised to a unit cube centred at the origin", f"source: {source.name}")
    image = base_color_image(mesh)
    if image is None:
        return obj_text(vertices, mesh.faces, comments).encode(), None, {}

    def png(picture) -> bytes:
        out = io.BytesIO()
        picture.save(out, format="PNG")
        return out.getvalue()

    uv = np.asarray(mesh.visual.uv, dtype=float)
    maps = {role: png(picture) for role, picture in pbr_images(mesh).items()}
    return obj_text(vertices, mesh.faces, comments, uv=uv, material_file=f"{stem}.mtl").encode(), png(image), maps
