"""Source text -> AST (prsc.syntax.nodes.Module); every syntax error becomes a PrscError."""

from __future__ import annotations

import dataclasses

import functools
from pathlib import Path

from lark import Lark, Token, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken, VisitError

from prsc.errors import PrscError, Span
from prsc.syntax import nodes
from prsc.syntax.layout import Layout, LayoutError
from prsc.syntax.transform import ToAst, token_span

GRAMMAR = Path(__file__).with_name("grammar.lark")

# Terminal names -> what a user calls them.
_WORDS = {
    "NAME": "a name",
    "NUMBER": "a number",
    "STRING": "a string",
    "_NL": "end of line",
    "_INDENT": "an indented block",
    "_DEDENT": "the end of the block",
    "$END": "end of file",
    "COMPARE_OP": "a comparison",
}
_EXPRESSION_START = {"NAME", "NUMBER", "STRING", "LPAR", "LSQB", "LBRACE", "MINUS", "PLUS", "NOT",
                     "TRUE", "FALSE", "TOP", "BOTTOM", "FRONT", "BACK", "LEFT", "RIGHT", "DISTANCE"}
_SPECIFIER_START = {"WITH", "AT", "IN", "ON", "COMPLETELY", "LEFT", "RIGHT", "AHEAD", "BEHIND", "ABOVE",
                    "BELOW", "BEYOND", "ALIGNED", "FACING", "REACHABLE", "STABLY", "VISIBLE", "NOT"}
_OPERATORS = {"PLUS", "MINUS", "STAR", "SLASH", "COMPARE_OP", "DOT", "LPAR", "LSQB", "DEG", "_RELATIVE", "_AND",
              "_OR",
              # the relations of a task statement (docs/tasks.md), re-typed by the layout there only
              "T_IN", "T_ON", "T_COMPLETELY", "T_AT", "T_VISIBLE", "T_LEFT", "T_RIGHT", "T_AHEAD", "T_BEHIND",
              "T_ABOVE", "T_BELOW", "TOUCHES", "HOLDS", "UPRIGHT"}
# A spec is a page of text. This bounds parse time and memory: lark's LALR parser is
# linear but takes ~30 us and ~0.7 kB per token, so 256 KiB of `1+1+...` parses in ~8 s.
MAX_SOURCE_BYTES = 256 * 1024
MAX_TREE_DEPTH = 200  # where `nested too deeply` points when the tree is deeper than Python's stack


@functools.lru_cache(maxsize=1)
def _parser() -> Lark:
    """The LALR parser, built once per process (and cached on disk by lark)."""
    return Lark(
        GRAMMAR.read_text(encoding="utf-8"),
        parser="lalr",
        lexer="basic",
        postlex=Layout(),
        propagate_positions=True,
        maybe_placeholders=True,
        cache=True,
    )


def _describe_terminal(name: str) -> str:
    """A terminal as a user reads it: `with`, `(`, a name, end of line."""
    if name in _WORDS:
        return _WORDS[name]
    try:
        pattern = _parser().get_terminal(name).pattern
    except KeyError:
        return name.lower()
    if pattern.type == "str":
        return f"'{pattern.value}'"
    return name.lower()


def _describe_expected(expected: set[str]) -> str:
    """The set of acceptable terminals in user words, grouped."""
    parts: list[str] = []
    rest = set(expected)
    if "NAME" in rest:
        rest.discard("JOINT")  # `joint` after `with` is a name re-typed by the layout
    if "WITH" in rest and "AT" in rest:
        parts.append("a specifier (with, at, in, on, left of, ahead of, facing, ...)")
        rest -= _SPECIFIER_START
    if {"NAME", "NUMBER", "LPAR"} <= rest:
        parts.append("an expression")
        rest -= _EXPRESSION_START
    if len(rest & _OPERATORS) >= 4:
        parts.append("an operator")
        rest -= _OPERATORS
    for name in sorted(rest, key=lambda t: (t.startswith("_") or t == "$END", t)):
        parts.append(_describe_terminal(name))
    if not parts:
        return "nothing more here"
    if len(parts) > 8:
        parts = parts[:8] + ["..."]
    return ", ".join(parts[:-1]) + (" or " if len(parts) > 1 else "") + parts[-1]


def _describe_token(token: Token) -> str:
    """The offending token in user words."""
    if token.type == "NAME":
        return f"name '{token}'"
    if token.type == "NUMBER":
        return f"number {token}"
    if token.type == "STRING":
        text = str(token)
        return f"string {text if len(text) <= 30 else text[:27] + '...'}"
    if token.type in _WORDS:
        return _WORDS[token.type]
    return f"'{token}'"


def _acceptable(error: UnexpectedToken) -> set[str]:
    """The terminals really acceptable at the error (LALR's own set includes merged-state noise)."""
    try:
        accepted = set(error.interactive_parser.accepts())
    except Exception:  # noqa: BLE001 - fall back to lark's approximation, never fail while reporting
        accepted = set()
    return accepted or set(error.expected)


def _opened_by(error: UnexpectedToken) -> str | None:
    """CLASS or FOR: the keyword of the block whose indented body the parser waits for."""
    try:
        stack = error.interactive_parser.parser_state.value_stack
    except AttributeError:  # pragma: no cover - lark internals changed: keep the class wording
        return None
    for item in reversed(stack):
        if isinstance(item, Token) and item.type in ("CLASS", "FOR"):
            return item.type
    return None


def _unclosed_note(path: str, layout: Layout, token: Token) -> tuple[tuple[str, Span], ...]:
    """A note pointing at the innermost open bracket when the error is on a later line."""
    if layout.open_brackets and (token.line or 0) > (layout.open_brackets[-1].line or 0):
        bracket = layout.open_brackets[-1]
        return ((f"this '{bracket}' is not closed", token_span(path, bracket)),)
    return ()


def _syntax_error(path: str, error: UnexpectedInput) -> PrscError:
    """A lark error as a PrscError with a span and what was expected."""
    if isinstance(error, UnexpectedToken):
        token = error.token
        span = token_span(path, token)
        if token.type == "$END":
            span = Span(path, token.end_line or token.line or 1, token.end_column or token.column or 1,
                        token.end_line or token.line or 1, (token.end_column or token.column or 1) + 1)
        expected = _acceptable(error)
        if token.type == "_INDENT":
            return PrscError("unexpected indentation (only a class or loop body is indented)", span)
        if token.type == "NAME" and "WITH" in expected and "AT" in expected:
            return PrscError(f"unknown specifier '{token}'; expected {_describe_expected(expected)}", span)
        if "SECONDS" in expected:  # docs/tasks.md: `for T seconds`, `terminate after T seconds`
            return PrscError(f"unexpected {_describe_token(token)}; a time is written `T seconds` "
                             "(the unit is required)", span)
        if "_INDENT" in expected and len(expected) == 1:
            if _opened_by(error) == "FOR":
                return PrscError("expected an indented loop body (one statement per line)", span)
            return PrscError("expected an indented class body (`prop: value` lines)", span)
        return PrscError(f"unexpected {_describe_token(token)}; expected {_describe_expected(expected)}", span,
                         notes=_unclosed_note(path, _parser().options.postlex, token))
    if isinstance(error, UnexpectedCharacters):
        char = error.char
        shown = repr(char)[1:-1] if char.isprintable() else f"U+{ord(char):04X}"
        span = Span(path, error.line, error.column, error.line, error.column + 1)
        if char in "\"'":
            return PrscError("unterminated string", span)
        if char.isalpha():  # a letter the lexer refused: not ASCII
            return PrscError(f"unexpected character '{shown}': names are ASCII letters, digits and _ "
                             "(any text may go in a string)", span)
        return PrscError(f"unexpected character '{shown}'", span)
    if isinstance(error, UnexpectedEOF):  # pragma: no cover - LALR reports $END as a token
        return PrscError(f"unexpected end of file; expected {_describe_expected(set(error.expected))}", None)
    return PrscError(str(error), None)  # pragma: no cover


def decode_source(data: bytes, path: str) -> str:
    """The text of a spec file: UTF-8 (a BOM allowed); anything else is an error at its byte."""
    if len(data) > MAX_SOURCE_BYTES:
        size = f"{len(data) / 1e6:.1f} MB" if len(data) > MAX_SOURCE_BYTES + 1 else f"over {MAX_SOURCE_BYTES // 1024} KiB"
        raise PrscError(f"file too large ({size}; a spec may be at most "
                        f"{MAX_SOURCE_BYTES // 1024} KiB)", Span(path, 1, 1, 1, 1))
    return decode_text(data, path)


def decode_text(data: bytes, path: str) -> str:
    """UTF-8 text of any size (a BOM allowed); anything else is an error at the offending byte."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        line = data.count(b"\n", 0, error.start) + 1
        column = error.start - (data.rfind(b"\n", 0, error.start) + 1) + 1
        raise PrscError(f"the file is not valid UTF-8 text (byte 0x{data[error.start]:02x})",
                        Span(path, line, column, line, column + 1)) from None


def parse_source(text: str, path: str) -> nodes.Module:
    """Parse spec text (path is used in spans and errors) into an AST module."""
    tree = None
    try:
        tree = _parser().parse(text)
        return dataclasses.replace(ToAst(path).transform(tree), source=text)
    except UnexpectedInput as error:
        raise _syntax_error(path, error) from None
    except LayoutError as error:
        raise PrscError(error.message, token_span(path, error.token)) from None
    except VisitError as error:
        if isinstance(error.orig_exc, PrscError):
            raise error.orig_exc from None
        if isinstance(error.orig_exc, RecursionError):
            raise _too_deep(path, tree) from None
        raise
    except RecursionError:
        raise _too_deep(path, tree) from None


def _too_deep(path: str, tree: Tree | None) -> PrscError:
    """`nested too deeply` at the first node deeper than MAX_TREE_DEPTH (found without recursion)."""
    span = Span(path, 1, 1, 1, 1)
    stack = [(tree, 0)] if tree is not None else []
    while stack:
        node, depth = stack.pop()
        if not isinstance(node, Tree):
            continue
        if depth > MAX_TREE_DEPTH and getattr(node.meta, "line", None) is not None:
            meta = node.meta
            span = Span(path, meta.line, meta.column, meta.line, meta.column + 1)
            break
        stack.extend((child, depth + 1) for child in reversed(node.children))
    return PrscError(f"this expression is nested too deeply to compile (more than {MAX_TREE_DEPTH} levels)", span)


def parse_file(path: str | Path) -> nodes.Module:
    """Read and parse one spec file."""
    name = str(path)
    try:
        with open(path, "rb") as handle:
            # One byte past the limit is enough to refuse; reading on would never end on /dev/zero.
            data = handle.read(MAX_SOURCE_BYTES + 1)
    except IsADirectoryError:
        raise PrscError(f"{name} is a directory, not a spec file") from None
    except OSError as error:
        raise PrscError(f"cannot read {name}: {error.strerror or error}") from None
    return parse_source(decode_source(data, name), name)
