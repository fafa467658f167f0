"""Which containers an object rests inside: the pairs the box collision test leaves out.

`on X` for a container X (a class declaring an interior, docs/language.md "Containers")
puts the object on X's floor, inside X's box: the walls, not X's box, bound it there, so
the sampler does not test the object's box against X's. The walls are kept clear by the
placement's own rows instead: the footprint inside them (specifier_rows._rows_in_container).
"""

from __future__ import annotations

from prsc.constraints.state import LoweringState
from prsc.errors import PrscError
from prsc.geometry.container import ASSET_INTERIORS, PROPERTIES
from prsc.ir.models import model_of
from prsc.ir import model as ir
from prsc.ir.program import ObjectDecl


def declares_interior(low: LoweringState, name: str) -> bool:
    """Whether object `name` declares a container interior (as constants: the rows need them)."""
    decl = low.program.objects[low.index_of[name]]
    declared = [k for k in PROPERTIES if decl.prop(k) is not None]
    if not declared:
        return False
    known = low.facts.props.get(name, {})
    varying = [k for k in declared if k not in known]
    if varying:
        expr = decl.prop(varying[0])
        raise PrscError(f"{name}: a container's {', '.join(varying)} must be constants", expr.span if expr else decl.span)
    return True


def is_container_asset(low: LoweringState, name: str) -> bool:
    """Whether object `name` declares no interior but is built as a container asset (its own interior)."""
    decl = low.program.objects[low.index_of[name]]
    return model_of(low.facts.props.get(name, {}), decl.class_name) in ASSET_INTERIORS


def containers_rested_in(low: LoweringState, obj: ObjectDecl) -> tuple[int, ...]:
    """Indices of the containers the object is placed `on` or `in` (it rests on their floors): those
    declaring an interior, for `completely on` and `in` container assets too (specifiers.interior_of),
    furniture whose support surface (`shelf.boards[k]`) it stands on, and articulated objects
    it is placed on or in a link of (`cabinet.links["drawer"]`)."""
    found = []
    for spec in obj.specifiers:
        target = getattr(spec, "target", getattr(spec, "region", None))
        if isinstance(spec, (ir.On, ir.In)) and isinstance(target, ir.LinkRef) and isinstance(target.target, ir.ObjectRef):
            # On or in a link of an articulated object: inside that object's box, bounded by its links.
            found.append(low.index_of[target.target.name])
            continue
        if isinstance(spec, (ir.On, ir.StablyOn)) and isinstance(target, ir.SurfaceRef) \
                and isinstance(target.target, ir.ObjectRef):
            # On a furniture surface (a shelf's board): inside the furniture's box, bounded by its parts.
            found.append(low.index_of[target.target.name])
            continue
        if not (isinstance(spec, (ir.On, ir.StablyOn)) and isinstance(target, ir.ObjectRef)):
            continue
        name = target.name
        inside = isinstance(spec, ir.On) and (spec.completely or spec.inside)
        if declares_interior(low, name) or (inside and is_container_asset(low, name)):
            found.append(low.index_of[name])
    return tuple(sorted(set(found)))
