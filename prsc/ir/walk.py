"""Generic traversal of IR expressions: children, rebuilding, and name collection."""

from __future__ import annotations

import dataclasses
from typing import Callable, Iterator

from prsc.ir import model as ir


def children(expr: ir.Expr) -> Iterator[ir.Expr]:
    """The direct sub-expressions of an expression, in field order."""
    for f in dataclasses.fields(expr):
        value = getattr(expr, f.name)
        if isinstance(value, ir.Expr):
            yield value
        elif isinstance(value, tuple):
            for item in value:
                if isinstance(item, ir.Expr):
                    yield item
                elif isinstance(item, tuple):
                    for sub in item:
                        if isinstance(sub, ir.Expr):
                            yield sub


def rebuild(expr: ir.Expr, fn: Callable[[ir.Expr], ir.Expr | None]) -> ir.Expr:
    """Bottom-up copy: fn(node) may return a replacement (or None to keep the rebuilt node)."""
    changes = {}
    for f in dataclasses.fields(expr):
        if f.name in ("span", "type"):
            continue
        value = getattr(expr, f.name)
        if isinstance(value, ir.Expr):
            changes[f.name] = rebuild(value, fn)
        elif isinstance(value, tuple) and value:
            changes[f.name] = tuple(_rebuild_item(item, fn) for item in value)
    node = dataclasses.replace(expr, **changes) if changes else expr
    replacement = fn(node)
    return node if replacement is None else replacement


def _rebuild_item(item, fn):
    if isinstance(item, ir.Expr):
        return rebuild(item, fn)
    if isinstance(item, tuple):
        return tuple(rebuild(sub, fn) if isinstance(sub, ir.Expr) else sub for sub in item)
    return item


def walk(expr: ir.Expr) -> Iterator[ir.Expr]:
    """Every node of an expression tree, parents first (iterative: no recursion limit)."""
    stack = [expr]
    while stack:
        node = stack.pop()
        yield node
        stack.extend(reversed(list(children(node))))


def specifier_exprs(spec: ir.Specifier) -> Iterator[ir.Expr]:
    """The expressions a specifier holds."""
    for f in dataclasses.fields(spec):
        value = getattr(spec, f.name)
        if isinstance(value, ir.Expr):
            yield value


def referenced_objects(expr: ir.Expr) -> set[str]:
    """Names of scene objects an expression mentions directly."""
    return {node.name for node in walk(expr) if isinstance(node, ir.ObjectRef)}


def referenced_variables(expr: ir.Expr) -> set[str]:
    """Names of global variables an expression mentions directly."""
    return {node.name for node in walk(expr) if isinstance(node, ir.VarRef)}
