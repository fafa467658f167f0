"""Which containers an object rests inside: the pairs the box collision test leaves out.

`on X` for a container X (a class declaring an interior, docs/language.md "Containers")
puts the object on X's floor, inside X's box: the walls, not X's box, bound it there, so
the sampler does not test the object's box against X's.
"""

from __future__ import annotations

from prsc.constraints.state import LoweringState
from prsc.errors import PrscError
from prsc.geometry.container import PROPERTIES
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


def containers_rested_in(low: LoweringState, obj: ir.ObjectDecl) -> tuple[int, ...]:
    """Indices of the containers the object is placed `on` (it rests on their floors)."""
    found = []
    for spec in obj.specifiers:
        if isinstance(spec, ir.On) and isinstance(spec.target, ir.ObjectRef) and declares_interior(low, spec.target.name):
            found.append(low.index_of[spec.target.name])
    return tuple(sorted(set(found)))
