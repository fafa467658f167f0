"""Per-object evaluation order: properties and specifiers, topologically sorted."""

from __future__ import annotations

import dataclasses
from typing import Callable, Sequence, TypeVar

from prsc.errors import PrscError, Span
from prsc.ir import model as ir
from prsc.ir.program import SelfRef
from prsc.ir.walk import walk

N = TypeVar("N")


def _toposort(items: Sequence[N], before: Callable[[N, N], bool]) -> tuple[list[N], list[N] | None]:
    """Kahn's algorithm, stable (ties keep source order); returns (order, cycle or None)."""
    count = len(items)
    preds = [{j for j in range(count) if j != i and before(items[j], items[i])} for i in range(count)]
    done: list[int] = []
    remaining = set(range(count))
    while remaining:
        ready = [i for i in sorted(remaining) if not (preds[i] & remaining)]
        if not ready:
            # walk predecessors from any remaining node until one repeats: that is a cycle
            path: list[int] = []
            node = min(remaining)
            while node not in path:
                path.append(node)
                node = min(preds[node] & remaining)
            cycle = path[path.index(node):]
            cycle.reverse()  # in dependency order: each needs the one before it
            return [items[i] for i in done], [items[i] for i in cycle]
        done.append(ready[0])
        remaining.remove(ready[0])
    return [items[i] for i in done], None


def _spec_words(spec: ir.Specifier) -> str:
    from prsc.ir.format import format_specifier

    return f"`{format_specifier(spec)}`"


def order_specifiers(specs: Sequence[ir.Specifier]) -> tuple[ir.Specifier, ...]:
    """Specifiers in evaluation order; a property set twice or a dependency cycle is an error.

    `facing toward` makes orientation depend on position; position specifiers that erode by
    the box would read orientation, a false cycle. They read the orientation-free bound
    instead (orientation_free=True, "orientation" dropped from reads): docs/language.md section 12.
    """
    setters: dict[str, ir.Specifier] = {}
    for spec in specs:
        for prop in spec.sets:
            if prop != "position" and prop in setters:
                first = setters[prop]
                raise PrscError(f"{prop} is set twice on this object: by {_spec_words(first)} and by "
                                f"{_spec_words(spec)}", spec.span, notes=((f"{prop} is first set here", first.span),))
            setters.setdefault(prop, spec)
    orientation_from_position = any("orientation" in s.sets and "position" in s.reads for s in specs)
    if orientation_from_position:
        specs = [dataclasses.replace(s, reads=tuple(r for r in s.reads if r != "orientation"), orientation_free=True)
                 if "position" in s.sets and "orientation" in s.reads else s for s in specs]

    def before(a: ir.Specifier, b: ir.Specifier) -> bool:
        return bool(set(a.sets) & set(b.reads))

    ordered, cycle = _toposort(list(specs), before)
    if cycle is not None:
        first, second = cycle[0], cycle[1 % len(cycle)]
        needs_first = sorted(set(first.sets) & set(second.reads))
        needs_second = sorted(set(second.sets) & set(first.reads))
        raise PrscError(
            f"specifiers depend on each other in a cycle: {_spec_words(second)} needs "
            f"{', '.join(needs_first)} from {_spec_words(first)}, which needs {', '.join(needs_second)} "
            f"from {_spec_words(second)}" if needs_second else
            f"specifiers depend on each other in a cycle through {_spec_words(first)} and {_spec_words(second)}",
            second.span, notes=(("the other specifier in the cycle", first.span),))
    return tuple(ordered)


def self_reads(expr: ir.Expr, object_name: str | None) -> set[str]:
    """Properties of object_name (None: of `self` in a class template) that an expression reads."""
    if object_name is None:
        return {node.prop for node in walk(expr) if isinstance(node, SelfRef)}
    return {node.prop for node in walk(expr)
            if isinstance(node, ir.PropertyRef) and isinstance(node.target, ir.ObjectRef)
            and node.target.name == object_name}


def order_properties(props: dict[str, ir.Expr], spans: dict[str, Span], object_name: str | None,
                     class_name: str) -> tuple[tuple[str, ir.Expr], ...]:
    """Properties so each comes after the properties of its own object it reads (None: class templates)."""
    names = list(props)
    reads = {name: self_reads(props[name], object_name) & set(props) for name in names}
    ordered, cycle = _toposort(names, lambda a, b: a in reads[b])
    if cycle is not None:
        chain = " -> ".join(f"self.{n}" for n in [*cycle, cycle[0]])
        raise PrscError(f"the properties of {class_name} depend on each other in a cycle ({chain})",
                        spans[cycle[0]], notes=tuple((f"the default of {n}", spans[n]) for n in cycle[1:]))
    return tuple((name, props[name]) for name in ordered)
