"""Readable text for the AST (`prsc explain --stage syntax`): one node per line, children indented."""

from __future__ import annotations

from dataclasses import fields
from typing import Any

from prsc.errors import Span
from prsc.syntax.nodes import Node

_INDENT = "  "


def _is_leaf(value: Any) -> bool:
    """A value printed inline: a scalar, a span, or a tuple of those (e.g. FacePoint words)."""
    if isinstance(value, tuple):
        return all(not isinstance(item, (Node, tuple)) for item in value)
    return not isinstance(value, Node)


def _leaf(value: Any) -> str:
    if isinstance(value, Span):
        return f"{value.line}:{value.column}"
    return repr(value)


def _header(node: Node) -> str:
    """`ClassName line:col field=value ...` with the node's inline fields (other spans left out)."""
    parts = [f"{type(node).__name__} {_leaf(node.span)}"]
    for f in fields(node):
        value = getattr(node, f.name)
        if f.name != "span" and f.repr and not isinstance(value, Span) and _is_leaf(value):
            parts.append(f"{f.name}={_leaf(value)}")
    return " ".join(parts)


def _dump(value: Any, label: str, depth: int, out: list[str]) -> None:
    pad = _INDENT * depth
    if isinstance(value, Node):
        out.append(f"{pad}{label}{_header(value)}")
        for f in fields(value):
            child = getattr(value, f.name)
            if not _is_leaf(child):
                _dump(child, f"{f.name}: ", depth + 1, out)
    elif isinstance(value, tuple) and not _is_leaf(value):
        # A list of nodes (or of tuples such as dict items): one "- " entry per item.
        out.append(f"{pad}{label.rstrip()}")
        for item in value:
            _dump(item, "- ", depth + 1, out)
    else:
        out.append(f"{pad}{label}{_leaf(value)}")


def format_ast(node: Node) -> str:
    """An indented dump of an AST node and everything under it, each node with its line:col."""
    out: list[str] = []
    _dump(node, "", 0, out)
    return "\n".join(out) + "\n"
