"""Numbers as text in output files: shortest exact decimal, so values round-trip bit for bit."""

from __future__ import annotations

from typing import Iterable


def num(value: float) -> str:
    """Shortest exact text of a float ('0.1', '1e-09', '2'); zero is always '0'."""
    value = float(value)
    if value == 0.0:
        return "0"
    text = repr(value)
    return text[:-2] if text.endswith(".0") else text


_TEXTS: dict[tuple, str] = {}  # tuples already written: a part's size and pose repeat in every scene
_TEXTS_KEPT = 1 << 16


def nums(values: Iterable[float]) -> str:
    """Space-separated exact floats."""
    if type(values) is not tuple:
        return " ".join(num(v) for v in values)
    text = _TEXTS.get(values)
    if text is None:
        if len(_TEXTS) >= _TEXTS_KEPT:
            _TEXTS.clear()
        text = _TEXTS[values] = " ".join(num(v) for v in values)
    return text
