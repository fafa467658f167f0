"""Operations on concrete scene values: arithmetic, comparison, face points, attributes.

What compiled expressions (evaluate.py) call at run time; errors point at the expression.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from prsc.constraints.context import SceneContext
from prsc.constraints.values import ObjectValue, OrientedPoint, RegionValue, as_position
from prsc.errors import PrscError, Span

# Unit offsets of face-point words in the object's local frame.
_FACE_AXES = {
    "top": (2, 1.0),
    "bottom": (2, -1.0),
    "front": (1, 1.0),
    "back": (1, -1.0),
    "right": (0, 1.0),
    "left": (0, -1.0),
}


def error_at(message: str, span: Span | None) -> PrscError:
    return PrscError(message, span)


def is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def is_vector(v: Any) -> bool:
    return isinstance(v, np.ndarray) and v.shape == (3,)


def arith_operand(v: Any) -> Any:
    """Face points and objects act as their positions in arithmetic (compat)."""
    if isinstance(v, (OrientedPoint, ObjectValue)):
        return as_position(v)
    return v


def binary(op: str, a: Any, b: Any, span: Span | None) -> Any:
    """`a op b` for scalars, vectors and strings."""
    if is_number(a) and is_number(b):
        return finite(_binary(op, a, b, span), span)
    with np.errstate(over="ignore", invalid="ignore"):  # finite reports an overflow, with its place
        return finite(_binary(op, a, b, span), span)


def finite(value: Any, span: Span | None) -> Any:
    """The value of an arithmetic result, or an error at it when it overflowed to infinity.

    Caught here, where the expression is known: further on an infinite coordinate or size
    only shows as a solver failure with no location."""
    if isinstance(value, float):
        if not math.isfinite(value):
            raise error_at("the result is too large (it overflows to infinity)", span)
    elif isinstance(value, np.ndarray) and not np.isfinite(value).all():
        raise error_at("the result is too large (it overflows to infinity)", span)
    return value


def _binary(op: str, a: Any, b: Any, span: Span | None) -> Any:
    a = arith_operand(a)
    b = arith_operand(b)
    if is_number(a) and is_number(b):
        if op == "+":
            return a + b
        if op == "-":
            return a - b
        if op == "*":
            return a * b
        if op == "/":
            if b == 0:
                raise error_at("division by zero", span)
            return a / b
    elif is_vector(a) and is_vector(b) and op in "+-":
        return a + b if op == "+" else a - b
    elif is_vector(a) and is_number(b) and op in "*/":
        if op == "/" and b == 0:
            raise error_at("division by zero", span)
        return a * b if op == "*" else a / b
    elif is_number(a) and is_vector(b) and op == "*":
        return b * a
    elif isinstance(a, str) and isinstance(b, str) and op == "+":
        return a + b
    raise error_at(f"cannot apply {op!r} to {describe(a)} and {describe(b)}", span)


def describe(v: Any) -> str:
    """A short name of a value's kind for error messages."""
    if isinstance(v, bool):
        return "a bool"
    if is_number(v):
        return "a number"
    if is_vector(v):
        return "a vector"
    if isinstance(v, str):
        return "a string"
    if isinstance(v, ObjectValue):
        return "an object"
    if isinstance(v, OrientedPoint):
        return "a face point"
    if isinstance(v, RegionValue):
        return "a region"
    if isinstance(v, tuple):
        return "a list"
    return type(v).__name__


def compare(op: str, a: Any, b: Any, span: Span | None) -> bool:
    """`a op b` for numbers (and ==/!= for anything)."""
    if op in ("==", "!="):
        if is_vector(a) or is_vector(b):
            equal = is_vector(a) and is_vector(b) and bool(np.all(a == b))
        else:
            equal = a == b
        return equal if op == "==" else not equal
    if not (is_number(a) and is_number(b)):
        raise error_at(f"cannot compare {describe(a)} and {describe(b)} with {op!r}", span)
    if op == "<":
        return a < b
    if op == "<=":
        return a <= b
    if op == ">":
        return a > b
    if op == ">=":
        return a >= b
    raise error_at(f"unknown comparison {op!r}", span)


def truthy(v: Any, span: Span | None) -> bool:
    """A value used as a condition."""
    if isinstance(v, bool):
        return v
    if is_number(v):
        return v != 0
    raise error_at(f"expected a condition, got {describe(v)}", span)


def face_point(target: Any, words: tuple[str, ...], span: Span | None) -> OrientedPoint:
    """`top back X` etc.: X.position + R_X . offset, carrying X's orientation."""
    if not isinstance(target, ObjectValue):
        raise error_at(f"a face point needs an object, got {describe(target)}", span)
    if target.position is None or target.rotation is None or target.dims is None:
        raise error_at(f"{target.name} is not placed yet here", span)
    offset = [0.0, 0.0, 0.0]
    for word in words:
        axis, sign = _FACE_AXES[word]
        offset[axis] = sign * target.dims[axis] * 0.5
    return OrientedPoint(target.position + target.rotation @ np.array(offset), target.rotation)


def relative_to(value: Any, frame: Any, span: Span | None) -> np.ndarray:
    """`V relative to X`: X.position + R_X V for an object or face point, X + V for a vector."""
    v = arith_operand(value)
    if not is_vector(v):
        raise error_at(f"'relative to' needs a vector on its left, got {describe(value)}", span)
    if isinstance(frame, (ObjectValue, OrientedPoint)):
        pos = as_position(frame)
        if pos is None or frame.rotation is None:
            raise error_at("the frame of 'relative to' is not placed yet here", span)
        return pos + frame.rotation @ v
    if is_vector(frame):
        return frame + v
    raise error_at(f"'relative to' needs an object or a vector on its right, got {describe(frame)}", span)


def attribute(target: Any, prop: str, ctx: SceneContext | None, span: Span | None) -> Any:
    """`target.prop` on an object, a face point or a vector."""
    if isinstance(target, ObjectValue):
        return target.get(prop, ctx, span)
    if isinstance(target, OrientedPoint):
        if prop == "position":
            return target.position
        if prop == "orientation":
            return target.rotation
        if prop in ("x", "y", "z"):
            return float(target.position["xyz".index(prop)])
    elif is_vector(target):
        if prop in ("x", "y", "z"):
            return float(target["xyz".index(prop)])
        if prop == "position":
            return target
    raise error_at(f"{describe(target)} has no attribute {prop!r}", span)


def as_number(v: Any, what: str, span: Span | None) -> float:
    if not is_number(v):
        raise error_at(f"{what} must be a number, got {describe(v)}", span)
    return float(v)


def distance(source: Any, target: Any, span: Span | None) -> float:
    """`distance from A to B`: the Euclidean distance between two positions (an object's centre)."""
    a, b = as_position(source), as_position(target)
    if a is None or b is None:
        raise error_at(f"distance needs two objects, face points or vectors, not {describe(source if a is None else target)}", span)
    return float(np.linalg.norm(np.asarray(a, dtype=float) - np.asarray(b, dtype=float)))
