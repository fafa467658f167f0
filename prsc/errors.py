"""Source spans and the one error type every stage raises for bad user input."""

from __future__ import annotations

import os
import stat
from dataclasses import dataclass


@dataclass(frozen=True)
class Span:
    """A region of a source file: 1-based line and column of its start and end."""

    path: str
    line: int
    column: int
    end_line: int
    end_column: int

    def __str__(self) -> str:
        return f"{self.path}:{self.line}:{self.column}"


class PrscError(Exception):
    """A user-facing error: reported as `path:line:col: error: message`, exit code 2."""

    def __init__(self, message: str, span: Span | None = None, notes: tuple[tuple[str, Span | None], ...] = (),
                 obj: str | None = None):
        super().__init__(message)
        self.message = message
        self.span = span
        self.notes = tuple(notes)
        # The scene object at fault, when a later stage (a backend) knows no span: the
        # command that has the spec's IR then reports the object's line.
        self.obj = obj


# Bounds on reading a source line for the caret: a line of /dev/zero or of a huge
# minified file never ends, and the error must still be printed.
_CHUNK_BYTES = 1024 * 1024
_SCAN_BYTES = 64 * 1024 * 1024


def read_error(error: OSError, path: object) -> PrscError:
    """`cannot read PATH: reason` for an input prsc could not read: named as the input it is,
    never as the output being written when it was found missing."""
    return PrscError(f"cannot read {path}: {os.strerror(error.errno) if error.errno else error}")


def _source_line(path: str, line: int) -> str | None:
    """The text of one line of a file (its first MiB), or None when it cannot be read as text."""
    try:
        # A FIFO is not read again: opening it would wait for a writer forever.
        mode = os.stat(path).st_mode
        if stat.S_ISFIFO(mode) or stat.S_ISSOCK(mode):
            return None
        with open(path, "rb") as handle:
            number, scanned = 1, 0
            while scanned <= _SCAN_BYTES:
                raw = handle.readline(_CHUNK_BYTES)
                if not raw:
                    return None
                if number == line:
                    return raw.decode("utf-8", errors="replace").rstrip("\r\n")
                scanned += len(raw)
                if raw.endswith(b"\n"):
                    number += 1
    except OSError:
        return None
    return None


def _caret_block(span: Span) -> str:
    """The source line of a span with a caret under its first column."""
    text = _source_line(span.path, span.line)
    if text is None:
        return ""
    text = text.expandtabs(1)
    if len(text) > 200:  # keep a minified or binary line readable
        start = max(0, span.column - 80)
        text = text[start : start + 160]
        col = span.column - start
    else:
        col = span.column
    width = 1
    if span.end_line == span.line and span.end_column > span.column:
        width = min(span.end_column - span.column, max(1, len(text) - col + 1))
    printable = "".join(ch if ch.isprintable() else "?" for ch in text)
    return f"    {printable}\n    {' ' * (col - 1)}{'^' * width}\n"


def format_error(error: PrscError, kind: str = "error") -> str:
    """Render an error as the compiler prints it to stderr."""
    if error.span is None:
        out = f"prsc: {kind}: {error.message}\n"
    else:
        out = f"{error.span}: {kind}: {error.message}\n" + _caret_block(error.span)
    for note, span in error.notes:
        if span is None:
            out += f"  note: {note}\n"
        else:
            out += f"{span}: note: {note}\n" + _caret_block(span)
    return out
