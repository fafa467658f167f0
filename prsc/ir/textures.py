"""`with texture "file.png"` (docs/language.md, "Meshes as you bring them"): an image on a
box's faces, wrapped round a cylinder or a sphere, found like a mesh. Checked here, at the line that names it, so `prsc check`
reports a missing or unreadable image as `compile` would."""

from __future__ import annotations

from dataclasses import replace
from typing import Sequence

from prsc.errors import PrscError
from prsc.ir import model as ir
from prsc.ir.mesh_sizes import constant_strings
from prsc.ir.program import ObjectDecl, Program
from prsc.user_assets.mesh_paths import TEXTURED_SHAPES, mesh_folders, read_image, resolve_mesh


def _checked(obj: ObjectDecl, texture: ir.Expr, folders: Sequence[str]) -> ObjectDecl:
    shape = obj.prop("shape")
    if not (isinstance(shape, ir.Const) and str(shape.value).strip().lower() in TEXTURED_SHAPES):
        raise PrscError(f"{obj.name}: `texture` puts an image on a box, cylinder or sphere, and this object is none "
                        "of them (a mesh brings its own texture)", texture.span)
    names = constant_strings(texture)
    if names is None:
        raise PrscError(f"{obj.name}: `texture` must be a file name, or a choice among file names", texture.span)
    for raw in names:
        try:
            read_image(resolve_mesh(raw, folders, anywhere=True, what="texture"))
        except PrscError as error:
            raise PrscError(f"{obj.name}: {error.message}", texture.span) from None
    return obj


def with_textures(program: Program, include_dirs: Sequence[str] = ()) -> Program:
    """The program, every `texture` checked: on a box, cylinder or sphere, naming images that exist and read."""
    folders = mesh_folders(program.path, include_dirs)
    objects = tuple(o if o.prop("texture") is None else _checked(o, o.prop("texture"), folders) for o in program.objects)
    return replace(program, objects=objects)
