"""Mesh objects as users bring them: `with mesh` implies the mesh shape, and the sizes the
spec leaves unset come from the mesh file's own bounds times `scale` (docs/language.md,
"Meshes as you bring them")."""

from __future__ import annotations

from dataclasses import replace
from typing import Sequence

from prsc.errors import PrscError
from prsc.ir import model as ir
from prsc.ir.program import ObjectDecl, Program
from prsc.ir.builtins import BUILTIN_SPAN
from prsc.ir.checks import SIZES
from prsc.ir.scope import did_you_mean
from prsc.user_assets.mesh_paths import MESH_COLLISIONS, UP_AXES, mesh_extent, mesh_folders, missing_texture_images, resolve_mesh


def _builtin(expr: ir.Expr | None) -> bool:
    """Whether a property still holds Object's built-in default (nothing in the spec set it)."""
    return expr is not None and expr.span.path == BUILTIN_SPAN.path


def constant_strings(expr: ir.Expr) -> tuple[str, ...] | None:
    """The file names a mesh expression can take when all are constants, else None."""
    if isinstance(expr, ir.Const) and expr.type == ir.Type.STRING:
        return (str(expr.value),)
    if isinstance(expr, ir.Distribution) and expr.kind in ("uniform", "discrete"):
        items = expr.args[0].items if len(expr.args) == 1 and isinstance(expr.args[0], ir.ListExpr) else expr.args
        if all(isinstance(a, ir.Const) and a.type == ir.Type.STRING for a in items):
            return tuple(str(a.value) for a in items)  # type: ignore[union-attr]
    return None


def _mesh_file(obj: ObjectDecl, raw: str, mesh: ir.Expr, folders: Sequence[str]):
    """The mesh file `raw` names, or an error at the expression that names it."""
    try:
        # Existence only: whether a path outside the spec's folders may be read is the
        # compiling command's decision (--meshes-anywhere).
        found = resolve_mesh(raw, folders, anywhere=True)
    except PrscError as error:
        raise PrscError(f"{obj.name}: {error.message}", mesh.span) from None
    missing = missing_texture_images(found)
    if missing:
        raise PrscError(f"{obj.name}: mesh {raw!r} names a texture image or material file that does not exist: "
                        f"{missing[0]}", mesh.span)
    return found


def _up_axis(obj: ObjectDecl, props: dict[str, ir.Expr]) -> str:
    """The object's constant `upAxis` ("+z" when unset), or an error at its value."""
    expr = props.get("upAxis")
    if expr is None:
        return "+z"
    value = str(expr.value).strip().lower() if isinstance(expr, ir.Const) else None
    if value in ("y", "x", "z"):
        value = "+" + value
    if value not in UP_AXES:
        shown = repr(expr.value) if isinstance(expr, ir.Const) else "a value that is not a constant"
        raise PrscError(f"{obj.name}: upAxis is {shown}; it is one constant of {', '.join(UP_AXES)}"
                        f"{did_you_mean(str(getattr(expr, 'value', '')), UP_AXES)}", expr.span)
    return value


def _sized(obj: ObjectDecl, mesh: ir.Expr, folders: Sequence[str]) -> ObjectDecl:
    """`obj` with the mesh shape and the unset sizes taken from its mesh file."""
    props = dict(obj.properties)
    shape = props.get("shape")
    if _builtin(shape):
        props["shape"] = ir.Const(mesh.span, ir.Type.STRING, "mesh")
    elif not (isinstance(shape, ir.Const) and str(shape.value).strip().lower() == "mesh"):
        return obj  # another shape (or one drawn at random) was asked for: the mesh is not used
    collision = props.get("collision")
    if isinstance(collision, ir.Const) and str(collision.value).strip().lower() not in MESH_COLLISIONS:
        raise PrscError(f"unknown collision {collision.value!r} for a mesh (one of {', '.join(MESH_COLLISIONS)})"
                        f"{did_you_mean(str(collision.value), MESH_COLLISIONS)}", collision.span)
    up_axis = _up_axis(obj, props)
    if "upAxis" in props:
        props["upAxis"] = ir.Const(props["upAxis"].span, ir.Type.STRING, up_axis)  # the JSON holds one spelling
    names = constant_strings(mesh)
    files = [_mesh_file(obj, raw, mesh, folders) for raw in names or ()]
    unset = [i for i, prop in enumerate(SIZES) if _builtin(props.get(prop))]
    if unset and len(files) != 1:
        raise PrscError(f"{obj.name}: the mesh is not one constant file, so its size cannot come from its "
                        f"bounds; give {', '.join(SIZES[i] for i in unset)}", mesh.span)
    if unset:
        try:
            extent = mesh_extent(files[0], up_axis)
        except PrscError as error:
            raise PrscError(f"{obj.name}: {error.message}", mesh.span) from None
        scale = props.get("scale")
        for i in unset:
            if extent[i] <= 0:
                raise PrscError(f"{obj.name}: the mesh is flat along {'xyz'[i]}; give {SIZES[i]}", mesh.span)
            size = ir.Const(mesh.span, ir.Type.SCALAR, extent[i])
            props[SIZES[i]] = size if scale is None else ir.BinOp(mesh.span, ir.Type.SCALAR, "*", size, scale)
    return replace(obj, properties=tuple((name, props[name]) for name in dict(obj.properties)))


def with_mesh_sizes(program: Program, include_dirs: Sequence[str] = ()) -> Program:
    """The program with every mesh object's shape and unset sizes filled in from its file."""
    folders = mesh_folders(program.path, include_dirs)
    objects = tuple(o if o.prop("mesh") is None else _sized(o, o.prop("mesh"), folders) for o in program.objects)
    return replace(program, objects=objects)
