"""Where a `with mesh "path"` file is found: the spec's folder, the --include folders, then
prsc's model library (the repository's specs/, as for imports), and nowhere else.

A path that is absolute or climbs out of those folders with `..` is read only when the
user says so (`--meshes-anywhere`): a spec from elsewhere cannot make prsc copy any
readable file into its outputs.

Also what every stage reads of a mesh file: its triangles turned upright (`upAxis`), its
UVs and base-colour image, and the copies MuJoCo needs to read an OBJ whole.
"""

from __future__ import annotations

import os
from functools import lru_cache
from pathlib import Path
from typing import Sequence

from prsc.errors import PrscError

MESH_COLLISIONS = ("hull", "decomposed")
TEXTURED_SHAPES = ("box", "cylinder", "sphere")  # the primitives `with texture` shows an image on
"""A mesh object's `collision`: its convex hull (every simulator's default), or the convex
pieces of a CoACD decomposition (docs/backends.md, "Mesh collision")."""


def _inside(path: str, folder: str) -> bool:
    """Whether `path` lies lexically inside `folder` (no `..` escape)."""
    folder = os.path.normpath(os.path.abspath(folder))
    return os.path.normpath(os.path.abspath(path)).startswith(folder.rstrip(os.sep) + os.sep)


LIBRARY = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "specs")
"""prsc's model library (specs/ beside the package), searched last, as for imports."""


def mesh_folders(spec: str, include_dirs: Sequence[str] = ()) -> tuple[str, ...]:
    """The folders meshes of `spec` are looked up in, in order."""
    return (os.path.dirname(os.path.abspath(spec)), *include_dirs, LIBRARY)


def resolve_mesh(raw: str, folders: Sequence[str], anywhere: bool = False, what: str = "mesh") -> Path:
    """The `what` file (a mesh, a texture, an asset) `raw` names, or a PrscError saying why it
    cannot be used."""
    if not raw or "\0" in raw:
        raise PrscError(f"{what} path {raw!r} is not a file name")
    if os.path.isabs(raw):
        candidates = [raw]
    else:
        candidates = [os.path.join(folder, raw) for folder in folders]
    for candidate in candidates:
        if not os.path.isfile(candidate):
            continue
        if not anywhere and not any(_inside(candidate, folder) for folder in folders):
            raise PrscError(f"{what} file {raw!r} is outside the spec's folder and the --include folders; "
                            "pass --meshes-anywhere to read it")
        return Path(candidate).resolve()
    if os.path.isabs(raw):
        raise PrscError(f"{what} file {raw!r} not found")
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
    raise PrscError(f"{what} file {raw!r} not found in {where}")


def distinct_folders(folders: Sequence[str]) -> tuple[str, ...]:
    """`folders` as absolute paths, each once, in order (`-I .` beside the spec adds nothing)."""
    return tuple(dict.fromkeys(os.path.normpath(os.path.abspath(folder)) for folder in folders))


UP_AXES = ("+z", "+y", "+x", "-z", "-y", "-x")
"""The values of `upAxis`: the file's axis that points up once the mesh is placed."""

_UP_ROTATIONS = {  # rows: the file's x, y, z axes written in the upright frame
    "+z": ((1, 0, 0), (0, 1, 0), (0, 0, 1)),
    "-z": ((1, 0, 0), (0, -1, 0), (0, 0, -1)),  # half a turn about x
    "+y": ((1, 0, 0), (0, 0, 1), (0, -1, 0)),  # a quarter turn about x: y -> z, z -> -y
    "-y": ((1, 0, 0), (0, 0, -1), (0, 1, 0)),
    "+x": ((0, 0, 1), (0, 1, 0), (-1, 0, 0)),  # a quarter turn about y: x -> z, z -> -x
    "-x": ((0, 0, -1), (0, 1, 0), (1, 0, 0)),
}


def up_rotation(up_axis: str) -> tuple[tuple[int, int, int], ...]:
    """The rotation (rows: the file's axes in the upright frame) that turns `up_axis` to +z."""
    try:
        return _UP_ROTATIONS[up_axis]  # type: ignore[return-value]
    except KeyError:
        raise PrscError(f"upAxis {up_axis!r} is not one of {', '.join(UP_AXES)}") from None


def mesh_extent(path: Path | str, up_axis: str = "+z") -> tuple[float, float, float]:
    """The extent (x, y, z) of a mesh file's bounding box once turned upright, in the file's units."""
    stat = os.stat(path)
    return _mesh_extent(str(path), stat.st_mtime_ns, stat.st_size, up_axis)


@lru_cache(maxsize=256)
def _mesh_extent(path: str, mtime_ns: int, size: int, up_axis: str) -> tuple[float, float, float]:
    """Bounds of a mesh file (cached while the file is unchanged)."""
    low, high = load_mesh(path, up_axis).bounds
    return tuple(float(v) for v in high - low)  # type: ignore[return-value]


def obj_material_files(path: Path) -> list[Path]:
    """The material files an OBJ names, then the base-colour images (`map_Kd`) those name."""
    if path.suffix.lower() != ".obj":
        return []
    named = []
    for line in path.read_text(encoding="utf-8", errors="replace").splitlines():
        if not line.startswith("mtllib "):
            continue
        library = path.parent / line.split(None, 1)[1].strip()
        named.append(library)
        if library.is_file():
            for entry in library.read_text(encoding="utf-8", errors="replace").splitlines():
                words = entry.split()
                if words and words[0] == "map_Kd" and len(words) > 1:
                    named.append(library.parent / words[-1])
    return named


def missing_texture_images(path: Path | str) -> tuple[str, ...]:
    """The texture images an OBJ's material files name that do not exist (trimesh skips them silently)."""
    return tuple(str(p) for p in obj_material_files(Path(path)) if not p.is_file())


def obj_texture_image(path: Path | str) -> Path | None:
    """The first base-colour image an OBJ's materials name and that exists, or None."""
    images = [p for p in obj_material_files(Path(path)) if p.suffix.lower() != ".mtl" and p.is_file()]
    return images[0] if images else None


def obj_text(vertices, faces, comments: Sequence[str] = (), uv=None, material_file: str | None = None) -> str:
    """A triangle mesh as OBJ text (vertices with full precision, 1-based faces); with `uv` (one
    texture coordinate per vertex) and `material_file`, textured by that file's material "texture"."""
    lines = [f"# {c}" for c in comments]
    if uv is not None:
        lines += [f"mtllib {material_file}", "usemtl texture"]
    lines += [f"v {x!r} {y!r} {z!r}" for x, y, z in vertices.tolist()]
    if uv is None:
        lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces.tolist()]
    else:
        lines += [f"vt {u!r} {v!r}" for u, v in uv.tolist()]
        lines += [f"f {a + 1}/{a + 1} {b + 1}/{b + 1} {c + 1}/{c + 1}" for a, b, c in faces.tolist()]
    return "\n".join(lines) + "\n"


def base_color_image(mesh):
    """The base-colour texture (a PIL image) of a trimesh mesh with UVs, or None."""
    visual = mesh.visual
    if getattr(visual, "kind", None) != "texture" or getattr(visual, "uv", None) is None:
        return None
    if len(visual.uv) != len(mesh.vertices):
        return None
    material = visual.material
    # OBJ/MTL gives a SimpleMaterial (map_Kd), glTF a PBRMaterial (baseColorTexture).
    return getattr(material, "image", None) or getattr(material, "baseColorTexture", None)


PBR_MAPS = ("normal", "orm")  # the maps a textured mesh keeps beside its base colour, in this order


def pbr_images(mesh) -> dict[str, object]:
    """The normal map and the occlusion-roughness-metallic map (PIL images, by PBR_MAPS role)
    of a glTF mesh that `base_color_image` found textured, those it has. glTF packs roughness
    in G and metallic in B of one image, the layout MuJoCo's `orm` role and UsdPreviewSurface's
    channels read."""
    material = mesh.visual.material
    images = {"normal": getattr(material, "normalTexture", None), "orm": getattr(material, "metallicRoughnessTexture", None)}
    return {role: image for role, image in images.items() if image is not None}


def read_trimesh(path: Path | str, **options):
    """`trimesh.load(path, **options)` without trimesh's numpy warnings on OBJ faces that lack UVs."""
    import warnings

    import trimesh

    with warnings.catch_warnings():
        # trimesh takes a median over the faces' texture coordinates, which is all NaN where
        # an OBJ's faces have none (pybullet's Franka meshes): numpy warns, the mesh is right.
        warnings.filterwarnings("ignore", category=RuntimeWarning, module=r"trimesh\.")
        return trimesh.load(path, **options)


def load_mesh(path: Path | str, up_axis: str = "+z"):
    """The triangles of a mesh file, turned so `up_axis` points up, as a trimesh.Trimesh (with
    its UVs and material when textured), or a PrscError saying why not."""
    import trimesh

    rotation = up_rotation(up_axis)
    try:
        mesh = read_trimesh(path, force="mesh")
    except Exception:  # trimesh raises many types for unreadable files
        # Its message may quote the file (a token of a text file): say only what failed.
        raise PrscError(f"cannot read mesh {path}: not a mesh file trimesh can load "
                        "(STL, OBJ, PLY, OFF, GLB/GLTF, ...)") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise PrscError(f"mesh {path} holds no triangles")
    if up_axis != "+z":
        import numpy as np

        mesh.vertices = np.asarray(mesh.vertices) @ np.asarray(rotation, dtype=float)
    return mesh


MUJOCO_MESHES = (".stl", ".obj", ".msh")  # what MuJoCo decodes; a URDF's other meshes are converted


def obj_copy(path: str | Path, cache: Path) -> tuple[str, tuple[float, float, float, float] | None]:
    """An OBJ copy (in `cache`, by content) of a mesh MuJoCo cannot decode (a ROS URDF's COLLADA
    `.dae`, a PLY), its parts joined where the file places them, and their area-weighted colour
    (None without one): the colour goes on the URDF visual, since the copy has no material."""
    import hashlib

    import numpy as np

    from prsc.files import atomic_write

    source = Path(path)
    target = cache / hashlib.sha256(source.read_bytes()).hexdigest()[:16] / f"{source.stem}.obj"
    colour_file = target.with_suffix(".rgba")
    if not target.is_file():
        try:
            scene = read_trimesh(source, force="scene")
            parts = [geometry for geometry in scene.dump() if len(getattr(geometry, "faces", ())) > 0]
        except Exception:  # trimesh (and pycollada) raise many types for unreadable files
            raise PrscError(f"cannot read mesh {source}: not a mesh file trimesh can load") from None
        if not parts:
            raise PrscError(f"mesh {source} holds no triangles")
        colours = [(part.area, _main_colour(part)) for part in parts]
        known = [(area, colour) for area, colour in colours if colour is not None]
        target.parent.mkdir(parents=True, exist_ok=True)
        if known:
            mean = np.average([c for _, c in known], axis=0, weights=[a for a, _ in known])
            atomic_write(colour_file, " ".join(repr(float(v)) for v in mean))
        vertices = np.vstack([part.vertices for part in parts])
        offsets = np.cumsum([0] + [len(part.vertices) for part in parts[:-1]])
        faces = np.vstack([part.faces + offset for part, offset in zip(parts, offsets)])
        atomic_write(target, obj_text(vertices, faces, (f"prsc: {source.name} as OBJ",)))
    colour = tuple(float(v) for v in colour_file.read_text().split()) if colour_file.is_file() else None
    return str(target), colour  # type: ignore[return-value]


def _main_colour(mesh) -> tuple[float, ...] | None:
    """A trimesh part's colour as RGBA in [0, 1]: its material's main colour or its faces' mean."""
    import numpy as np

    visual = mesh.visual
    material = getattr(visual, "material", None)
    if material is not None and getattr(material, "main_color", None) is not None:
        return tuple(np.asarray(material.main_color, float) / 255.0)
    if getattr(visual, "kind", None) in ("face", "vertex"):
        return tuple(np.asarray(visual.face_colors, float).mean(axis=0) / 255.0)
    return None


def obj_objects(path: str | Path) -> int:
    """How many objects (`o`/`g` groups) with faces an OBJ file holds."""
    counted, faces = 0, False
    try:
        with open(path, encoding="utf-8", errors="replace") as text:
            for line in text:
                if line.startswith(("o ", "g ")):
                    counted, faces = counted + faces, False
                elif line.startswith("f "):
                    faces = True
    except OSError:
        return 0
    return counted + faces


def one_object_obj(path: str | Path, cache: Path) -> str:
    """A one-object copy of an OBJ of several objects, with its UVs if it has them, in `cache` (by content)."""
    import hashlib

    import trimesh

    from prsc.files import atomic_write

    source = Path(path)
    target = cache / hashlib.sha256(source.read_bytes()).hexdigest()[:16] / source.name
    if not target.is_file():
        # As written (no merging), so each vertex keeps its own texture coordinate.
        loaded = read_trimesh(source, force="mesh", process=False, maintain_order=True)
        comments = (f"prsc: {source.name} as one object",)
        uv = getattr(loaded.visual, "uv", None)
        if uv is not None and len(uv) == len(loaded.vertices):  # textured: keep its UVs (MuJoCo reads `vt`)
            text = obj_text(loaded.vertices, loaded.faces, comments, uv=uv, material_file=f"{source.stem}.mtl")
        else:
            mesh = trimesh.Trimesh(loaded.vertices, loaded.faces)  # MuJoCo takes colours from the asset file
            text = obj_text(mesh.vertices, mesh.faces, comments)
        target.parent.mkdir(parents=True, exist_ok=True)
        atomic_write(target, text)
    return str(target)


def png_image(path: Path | str, cache: Path) -> str:
    """`path` itself when it is a PNG, else a PNG copy of it in `cache` (MuJoCo reads PNG)."""
    import hashlib

    from prsc.files import atomic_write

    source = Path(path)
    if source.suffix.lower() == ".png":
        return str(source)
    target = cache / hashlib.sha256(source.read_bytes()).hexdigest()[:16] / f"{source.stem}.png"
    if not target.is_file():
        import io

        png = io.BytesIO()
        read_image(source).save(png, format="PNG")
        target.parent.mkdir(parents=True, exist_ok=True)
        atomic_write(target, png.getvalue())
    return str(target)


def read_image(path: Path | str):
    """The image file at `path` as an RGB(A) PIL image, or a PrscError saying why not."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as image:
            image.load()
            return image.convert("RGBA" if "A" in image.getbands() else "RGB")
    except (OSError, UnidentifiedImageError, ValueError):
        raise PrscError(f"cannot read image {path}: not an image file PIL reads (PNG, JPEG, ...)") from None


def mujoco_readable_meshes(spec, cache: Path) -> None:
    """Point every OBJ of an asset's MjSpec that MuJoCo would read in part at a copy (in `cache`)
    it reads whole, and give the geoms drawing a textured OBJ its image."""
    import mujoco

    images = {}
    for mesh in spec.meshes:
        image = obj_texture_image(mesh.file)
        if image is not None:
            images[mesh.name] = png_image(image, cache / "images")
        # MuJoCo reads only the first object of an OBJ: pybullet's tray/tray_textured4.obj, five
        # boxes, would be one wall of the tray in MuJoCo, and its box and convex hull that wall's.
        # The objects of such a file may overlap, so no volume is exact: a body's mass and inertia
        # computed from it take its convex hull, the shape it collides as.
        several = mesh.file.lower().endswith(".obj") and obj_objects(mesh.file) > 1
        if several or image is not None:  # textured: one UV per vertex, which MuJoCo maps right
            mesh.file = one_object_obj(mesh.file, cache / "one-object")
        if several:
            mesh.inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_CONVEX
    # MuJoCo's URDF import keeps an OBJ's UVs but not its MTL's image: a geom drawing a textured
    # mesh gets that image as its material (coloured by the file's own colour, as pybullet does).
    for name, image in images.items():
        texture = spec.add_texture(name=f"{name}_image", type=mujoco.mjtTexture.mjTEXTURE_2D, file=image,
                                   colorspace=mujoco.mjtColorSpace.mjCOLORSPACE_AUTO)
        material = spec.add_material(name=f"{name}_image")
        material.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = texture.name
    for geom in spec.geoms:
        if geom.meshname in images and not geom.material:
            geom.material = f"{geom.meshname}_image"
