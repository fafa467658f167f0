"""Which containers an object rests inside: the pairs the box collision test leaves out.

`on X` for a container X (a class declaring an interior, docs/language.md "Containers")
puts the object on X's floor, inside X's box: the walls, not X's box, bound it there, so
the sampler does not test the object's box against X's.
"""

from __future__ import annotations

from prsc.constraints.state import LoweringState
from prsc.errors import PrscError
from prsc.geometry.container import ASSET_INTERIORS, PROPERTIES
from prsc.ir.models import model_of
from prsc.ir import model as ir


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


def containers_rested_in(low: LoweringState, obj: ir.ObjectDecl) -> tuple[int, ...]:
    """Indices of the containers the object is placed `on` (it rests on their floors): those
    declaring an interior, and for `completely on` container assets too (specifiers.interior_of)."""
    found = []
    for spec in obj.specifiers:
        if not (isinstance(spec, ir.On) and isinstance(spec.target, ir.ObjectRef)):
            continue
        name = spec.target.name
        if declares_interior(low, name) or (spec.completely and is_container_asset(low, name)):
            found.append(low.index_of[name])
    return tuple(sorted(set(found)))
