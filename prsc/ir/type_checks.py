"""The IR's type checks: which types a place accepts, and the error when an expression has another."""

from __future__ import annotations

from prsc.errors import PrscError
from prsc.ir import model as ir

T = ir.Type
POINT_TYPES = frozenset({T.VECTOR, T.ORIENTED_POINT})
LOCATED_TYPES = frozenset({T.OBJECT, T.VECTOR, T.ORIENTED_POINT})


def type_words(types) -> str:
    """A set of types in words: 'a vector or an object'."""
    words = []
    for t in sorted(types, key=lambda t: t.value):
        if t == T.ANY:
            continue
        article = "an" if t.value[0] in "aeiou" else "a"
        words.append(f"{article} {t.value}")
    if not words:
        return "anything"
    return ", ".join(words[:-1]) + (" or " if len(words) > 1 else "") + words[-1]


def article(t: ir.Type) -> str:
    """'a scalar', 'an object'."""
    return ("an " if t.value[0] in "aeiou" else "a ") + t.value


def expect(expr: ir.Expr, types, what: str) -> ir.Expr:
    """expr itself when its type is one of types (or ANY); else a type error at its span."""
    if expr.type == T.ANY or expr.type in types:
        return expr
    raise PrscError(f"{what} must be {type_words(types)}, not {article(expr.type)}", expr.span)
