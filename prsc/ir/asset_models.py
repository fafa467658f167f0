"""Objects whose `model` is the user's own URDF or MJCF file (docs/assets.md): the file is
found and loaded here, at the line that names it, so `prsc check` reports what `compile`
would; the object's box becomes the file's, an articulated asset is fixed-base unless it
says `static False`, every `with joint "NAME" v` is checked against the file's joints, and
every `X.links["NAME"]` is read from X's file (its chain of bodies and collision boxes)."""

from __future__ import annotations

from dataclasses import fields, replace
from typing import Sequence

from prsc.user_assets.asset_files import (ROOT_OFFSET, ArticulatedAsset, asset_at, describe_asset, model_asset, names_asset,
                                          resolve_asset_file)
from prsc.user_assets.asset_fitting import library_arm
from prsc.user_assets.asset_links import AssetLink, asset_link, check_link_target
from prsc.user_assets.asset_scale import scaled_asset_file
from prsc.user_assets.cabinet_urdf import LIBRARY_NAME, cabinet_urdf
from prsc.errors import PrscError, Span
from prsc.ir import model as ir
from prsc.ir.builtins import BUILTIN_SPAN, joint_name, joint_property
from prsc.ir.checks import SIZES
from prsc.ir.format import format_expr
from prsc.ir.models import model_of
from prsc.ir.program import ClassDef, ObjectDecl, Program
from prsc.task.bind import link_object
from prsc.task.terms import TaskObject, TaskStatements
from prsc.ir.scope import did_you_mean
from prsc.ir.walk import rebuild, walk
from prsc.user_assets.mesh_paths import mesh_folders


def _declared_in(classes: dict[str, ClassDef], class_name: str, prop: str, span) -> str | None:
    """The class of the chain (most derived first) whose own body wrote `prop` at `span`."""
    cls = classes.get(class_name)
    while cls is not None:
        parent = classes.get(cls.parent) if cls.parent else None
        own = dict(cls.defaults).get(prop)
        inherited = dict(parent.defaults).get(prop) if parent is not None else None
        if own is not None and own.span == span and (inherited is None or inherited.span != span):
            return cls.name
        cls = parent
    return None


def _constant_range(expr: ir.Expr) -> tuple[float, float] | None:
    """(low, high) of a constant value or a uniform range of constants, else None."""
    if isinstance(expr, ir.Const) and isinstance(expr.value, (int, float)) and not isinstance(expr.value, bool):
        return float(expr.value), float(expr.value)
    if isinstance(expr, ir.Distribution) and expr.kind in ("range", "uniform", "discrete"):
        items = expr.args[0].items if len(expr.args) == 1 and isinstance(expr.args[0], ir.ListExpr) else expr.args
        ends = [_constant_range(a) for a in items if isinstance(a, ir.Expr)]
        if ends and all(e is not None for e in ends):
            return min(e[0] for e in ends), max(e[1] for e in ends)  # type: ignore[index]
    return None


def _check_joint(obj: ObjectDecl, asset: ArticulatedAsset, joint: str, value: ir.Expr) -> None:
    """An error at `value` when `joint` is not the asset's or the value leaves its limits."""
    found = asset.joint(joint)
    if found is None:
        names = [j.name for j in asset.joints]
        raise PrscError(f"{obj.name}: {asset.name} has no joint {joint!r}{did_you_mean(joint, names)} "
                        f"(its joints: {', '.join(names) or 'none'})", value.span)
    ends = _constant_range(value)
    if ends is not None and not (found.admits(ends[0]) and found.admits(ends[1])):
        unit = "rad" if found.kind == "revolute" else "m"
        raise PrscError(f"{obj.name}: joint {joint!r} value {ends[0]:g}" + (f"..{ends[1]:g}" if ends[1] != ends[0] else "")
                        + f" {unit} is outside its limits [{found.lower:g}, {found.upper:g}] {unit}", value.span)


def _scale_of(obj: ObjectDecl, scale: ir.Expr | None) -> float:
    """The constant `scale` of an asset from a file (1 without one); an error at the value otherwise."""
    if scale is None:
        return 1.0
    if not (isinstance(scale, ir.Const) and isinstance(scale.value, (int, float)) and not isinstance(scale.value, bool)
            and scale.value > 0):
        raise PrscError(f"{obj.name}: the `scale` of a URDF or MJCF asset must be a positive number, the same in every "
                        f"scene (it scales the file once), not {format_expr(scale)}", scale.span)
    return float(scale.value)


def _fitted(obj: ObjectDecl, model: ir.Const, folders: Sequence[str],
            classes: dict[str, ClassDef]) -> tuple[ObjectDecl, ArticulatedAsset]:
    """`obj` with the file's box, its base and its joints checked, and the file's description
    boxed as the object is."""
    props = dict(obj.properties)
    factor = _scale_of(obj, props.get("scale"))
    arm = library_arm(model.value)
    if arm is not None and factor != 1.0:
        raise PrscError(f"{obj.name}: the library's {arm.name} takes no `scale`", props["scale"].span)
    try:
        if arm is not None:  # the library's arm: its file and what the library adds, by its name
            asset = model_asset(str(model.value))
        else:
            # At a scale other than 1 the file is a scaled copy in the build folder (prsc/user_assets/asset_scale.py).
            path = scaled_asset_file(resolve_asset_file(str(model.value), folders), factor, folders)
            asset = describe_asset(path, folders)
            # Found once, here: every later stage and the backends read the file this names.
            props["model"] = ir.Const(model.span, ir.Type.STRING, str(path))
    except PrscError as error:
        raise PrscError(f"{obj.name}: {error.message}", model.span) from None
    tcp = props.get("tcp")
    if asset.has_joints and (tcp is not None or "Robot" in obj.class_chain):
        # A robot: the scene says so by its tool frame (a Robot subclass always has one).
        if tcp is None:
            props["tcp"] = ir.Const(model.span, ir.Type.STRING, asset.tcp or asset.root)
        elif not (isinstance(tcp, ir.Const) and str(tcp.value) in (*asset.links, *asset.sites)):
            shown = str(getattr(tcp, "value", ""))
            raise PrscError(f"{obj.name}: tcp {shown!r} is no link or site of {model.value}"
                            f"{did_you_mean(shown, (*asset.links, *asset.sites))}", tcp.span)
    if arm is not None and arm.fitting.fingers and "fingers" not in props:  # its finger links (`holds`)
        props["fingers"] = ir.ListExpr(model.span, ir.Type.LIST, tuple(
            ir.Const(model.span, ir.Type.STRING, finger) for finger in arm.fitting.fingers))
    static = props.get("static")
    # Fixed unless `static False`: an arm, or a URDF whose root has mass 0 (pybullet's fixed base).
    if (asset.has_joints or asset.fixed) and (static is None or static.span.path == BUILTIN_SPAN.path):
        props["static"] = ir.Const(model.span, ir.Type.BOOL, True)
    constants = {}
    for prop, value in obj.properties:
        joint = joint_name(prop)
        if joint is not None:
            _check_joint(obj, asset, joint, value)
            ends = _constant_range(value)
            if ends is not None and ends[0] == ends[1]:
                constants[joint] = ends[0]
    # The box is the file's at the joint values the spec sets to constants (the rest at home):
    # an arm whose home hangs below its root stands on its base once a joint lifts it.
    asset = asset_at(asset, folders, constants)
    model_class = _declared_in(classes, obj.class_name, "model", model.span)
    for size, extent in zip(SIZES, asset.size):
        written = props.get(size)
        if written is not None and written.span.path != BUILTIN_SPAN.path:
            in_object = written.span.path == obj.span.path and obj.span.line <= written.span.line <= obj.span.end_line
            in_own_class = model_class is not None and _declared_in(classes, obj.class_name, size, written.span) == model_class
            if in_object or in_own_class:
                raise PrscError(f"{obj.name}: the {size} of an asset from a file is the file's ({extent:.4g} m); "
                                f"remove `{size}`", written.span)
        props[size] = ir.Const(model.span, ir.Type.SCALAR, extent)
    # Where the file's root sits in that box: every later stage and backend mounts the file there.
    props[ROOT_OFFSET] = ir.Const(model.span, ir.Type.VECTOR, asset.root_offset)
    # Joints the spec leaves unset start at the file's home: the scene records every joint.
    order = [name for name in props if joint_name(name) is None]  # the object's own, then static and tcp if added
    for joint in asset.joints:
        prop = joint_property(joint.name)
        if prop not in props:
            props[prop] = ir.Const(model.span, ir.Type.SCALAR, joint.home)
        order.append(prop)
    return replace(obj, properties=tuple((name, props[name]) for name in order)), asset


def _no_file_joints(obj: ObjectDecl) -> None:
    """`with joint` on an object whose model is not a file is an error at the first one."""
    for prop, value in obj.properties:
        if joint_name(prop) is not None:
            raise PrscError(f"{obj.name}: `with joint` needs an object whose model is a URDF or MJCF file",
                            value.span)


def _library_cabinet(obj: ObjectDecl, model: ir.Const) -> ObjectDecl:
    """`model "cabinet"`: the library's cabinet written as a URDF from the object's width,
    length, height and `drawers` (constants), then read as any file asset is."""
    values = {}
    for name in (*SIZES, "drawers"):
        expr = obj.prop(name)
        if not (isinstance(expr, ir.Const) and expr.type == ir.Type.SCALAR):
            raise PrscError(f"{obj.name}: a library cabinet's {name} must be a constant number", (expr or model).span)
        values[name] = float(expr.value)
    drawers = int(values["drawers"]) if values["drawers"] == int(values["drawers"]) else values["drawers"]
    try:
        path = cabinet_urdf(values["width"], values["length"], values["height"], drawers)  # type: ignore[arg-type]
    except PrscError as error:
        raise PrscError(f"{obj.name}: {error.message}", (obj.prop("drawers") or model).span) from None
    props = dict(obj.properties)
    props["model"] = ir.Const(model.span, ir.Type.STRING, str(path))
    for name in SIZES:  # they made the file, and the file's box (_fitted) is theirs
        del props[name]
    return replace(obj, properties=tuple(props.items()))


def _named_arm(obj: ObjectDecl) -> ir.Const | None:
    """A library arm named without `model`: by the compat `model_name` or the class's name."""
    constants = {name: value.value for name, value in obj.properties if isinstance(value, ir.Const)}
    name = model_of(constants, obj.class_name)
    if library_arm(name) is None:
        return None
    return ir.Const((obj.prop("model_name") or obj).span, ir.Type.STRING, name)


def _linked(obj: ObjectDecl, assets: dict[str, ArticulatedAsset], folders: Sequence[str]) -> ObjectDecl:
    """`obj` with every `X.links["NAME"]` in its specifiers read from X's file (or an error there)."""

    def resolve(node: ir.Expr) -> ir.Expr | None:
        if not isinstance(node, ir.LinkRef):
            return None
        target = node.target
        asset = assets.get(target.name) if isinstance(target, ir.ObjectRef) else None
        link = _read_link(format_expr(target), asset, node.name, folders, node.span)
        return replace(node, link=link, root_offset=asset.root_offset)  # type: ignore[union-attr]

    specifiers = []
    for spec in obj.specifiers:
        linked = {f.name: getattr(spec, f.name) for f in fields(spec) if isinstance(getattr(spec, f.name), ir.Expr)
                  and any(isinstance(node, ir.LinkRef) for node in walk(getattr(spec, f.name)))}
        changes = {name: rebuild(expr, resolve) for name, expr in linked.items()}
        specifiers.append(replace(spec, **changes) if changes else spec)
    return replace(obj, specifiers=tuple(specifiers))


def _read_link(owner: str, asset: ArticulatedAsset | None, name: str, folders: Sequence[str], span: Span) -> AssetLink:
    """Link `name` of the asset of object `owner` (an error at `span` when it has no file or no such link)."""
    if asset is None:
        raise PrscError(f"{owner} has no links: only an object whose model is a URDF or MJCF file has them", span)
    try:
        return asset_link(asset, name, folders)
    except PrscError as error:
        raise PrscError(f"{owner}.links: {error.message}", span) from None


def _task_links(program: Program, assets: dict[str, ArticulatedAsset], folders: Sequence[str]) -> TaskStatements:
    """The task with every link it names read from its object's file (docs/tasks.md): an `in` or
    `on` a link that has no such surface is the sampler's error, at the task's line."""
    links: dict[str, TaskObject] = {}
    for ref in program.task_links:
        link = _read_link(ref.obj, assets.get(ref.obj), ref.link, folders, ref.span)
        if ref.relation is not None:
            check_link_target(f"{ref.obj}.links[{ref.link!r}]", link, ref.relation.endswith("in"),
                              ref.relation.startswith("completely"), ref.span)
        linked = link_object(ref.obj, ref.link, link.boxes)
        links.setdefault(linked.name, linked)
    return replace(program.task, links=tuple(links.values()))


def with_asset_models(program: Program, include_dirs: Sequence[str] = ()) -> Program:
    """The program with every file-model object fitted to its file (box, base, joints), and every
    link its specifiers name read from the file."""
    folders = mesh_folders(program.path, include_dirs)
    classes = {c.name: c for c in program.classes}
    objects = []
    assets: dict[str, ArticulatedAsset] = {}
    for obj in program.objects:
        obj = _linked(obj, assets, folders)  # a link's object comes earlier (it depends on it)
        model = obj.prop("model") or _named_arm(obj)
        if isinstance(model, ir.Const) and model.value == LIBRARY_NAME:
            obj = _library_cabinet(obj, model)
            model = obj.prop("model")
        if isinstance(model, ir.Const) and names_asset(model.value):
            obj, assets[obj.name] = _fitted(obj, model, folders, classes)
        else:
            _no_file_joints(obj)
        objects.append(obj)
    return replace(program, objects=tuple(objects), task=_task_links(program, assets, folders))
