"""Line layout between the lexer and the parser: newlines, indentation, bracket depth.

A statement continues on the next line inside brackets and after a trailing comma, so
those newlines are dropped. Every other newline is passed on, followed by _INDENT or
_DEDENT tokens when the indentation changes. The one contextual keyword, `joint` right after
`with`, is re-typed here (the grammar accepts them only in class
and loop bodies, so an indented top-level statement is a syntax error there, with its position).
"""

from __future__ import annotations

from typing import Iterator

from lark import Token
from lark.lark import PostLex

OPENING = {"LPAR": "(", "LSQB": "[", "LBRACE": "{"}
CLOSING = {"RPAR", "RSQB", "RBRACE"}
MAX_BRACKET_DEPTH = 100
TAB_SIZE = 8


class LayoutError(Exception):
    """A layout problem at a position (the parser front end adds the path)."""

    def __init__(self, message: str, token: Token):
        super().__init__(message)
        self.message = message
        self.token = token


def _indent_width(newline_token: str) -> int:
    """The indentation of the line a newline token leads to (tabs to multiples of 8)."""
    last = newline_token.rsplit("\n", 1)[-1]
    if "#" in last:  # the file ends in a comment: no next line
        return 0
    width = 0
    for ch in last:
        if ch == "\t":
            width = (width // TAB_SIZE + 1) * TAB_SIZE
        elif ch == " ":
            width += 1
    return width


def _indent_token(kind: str, newline: Token, width: int) -> Token:
    """An _INDENT/_DEDENT token placed at the first column of the next line's text."""
    line = (newline.end_line or newline.line or 1)
    return Token(kind, "", start_pos=newline.end_pos, line=line, column=width + 1,
                 end_line=line, end_column=width + 2, end_pos=newline.end_pos)


# docs/tasks.md: a line that starts with one of these words (not followed by `=`,
# `.`, `(`, `[` or `,`, which keep it a name) is a task statement, whose words are keywords
# only there.
TASK_STATEMENTS = {"goal": "GOAL", "fail": "FAIL", "terminate": "TERMINATE", "record": "RECORD"}
TASK_WORDS = {"when": "WHEN", "after": "AFTER", "seconds": "SECONDS", "second": "SECONDS", "initial": "RECORD_WHEN",
              "final": "RECORD_WHEN", "as": "AS", "touches": "TOUCHES", "holds": "HOLDS", "rest": "REST",
              "upright": "UPRIGHT"}
TASK_KEYWORDS = {"IN": "T_IN", "ON": "T_ON", "COMPLETELY": "T_COMPLETELY", "AT": "T_AT", "BY": "T_BY",
                 "VISIBLE": "T_VISIBLE", "AHEAD": "T_AHEAD", "BEHIND": "T_BEHIND", "ABOVE": "T_ABOVE",
                 "BELOW": "T_BELOW"}
FACE_DIRECTIONS = {"LEFT": "T_LEFT", "RIGHT": "T_RIGHT"}  # relations only before `of`, face words otherwise
_KEEP_NAME = {"=", ".", "(", "[", ","}


def _with_next(stream: Iterator[Token]) -> Iterator[tuple[Token, Token | None]]:
    """Each token with the one after it (None at the end)."""
    previous = None
    for token in stream:
        if previous is not None:
            yield previous, token
        previous = token
    if previous is not None:
        yield previous, None


def _task_token(token: Token, following: Token | None) -> Token:
    """A token of a task statement as the grammar's task rules read it."""
    kind = token.type
    if kind == "NAME" and str(token) in TASK_WORDS:
        kind = TASK_WORDS[str(token)]
    elif kind in TASK_KEYWORDS:
        kind = TASK_KEYWORDS[kind]
    elif kind in FACE_DIRECTIONS and following is not None and str(following) == "of":
        kind = FACE_DIRECTIONS[kind]
    return token if kind == token.type else Token.new_borrow_pos(kind, token, token)


class Layout(PostLex):
    """The post-lexer: drops continuation newlines and adds indentation tokens."""

    always_accept = ("_NL",)

    def __init__(self) -> None:
        self.open_brackets: list[Token] = []  # of the parse in progress (read when reporting errors)

    def process(self, stream: Iterator[Token]) -> Iterator[Token]:
        """Yield the parser's token stream."""
        brackets: list[Token] = []
        self.open_brackets = brackets
        indents = [0]
        last: Token | None = None
        in_task = False
        for token, following in _with_next(stream):
            kind = token.type
            if kind == "NAME" and (last is None or last.type == "_NL") and str(token) in TASK_STATEMENTS and (
                    following is not None and following.type != "_NL" and str(following) not in _KEEP_NAME):
                in_task = True
                token = Token.new_borrow_pos(TASK_STATEMENTS[str(token)], token, token)
            elif in_task and kind != "_NL":
                token = _task_token(token, following)
            if kind == "_NL":
                if brackets or (last is not None and last.type == "COMMA"):
                    continue
                in_task = False
                yield token
                width = _indent_width(token)
                if width > indents[-1]:
                    indents.append(width)
                    yield _indent_token("_INDENT", token, width)
                elif width < indents[-1]:
                    while width < indents[-1]:
                        indents.pop()
                        yield _indent_token("_DEDENT", token, width)
                    if width != indents[-1]:
                        raise LayoutError("this line's indentation matches no enclosing block",
                                          _indent_token("_DEDENT", token, width))
                last = token
                continue
            if last is None and token.column != 1:
                raise LayoutError("unexpected indentation (only a class or loop body is indented)", token)
            if kind in OPENING:
                brackets.append(token)
                if len(brackets) > MAX_BRACKET_DEPTH:
                    raise LayoutError(f"brackets nested more than {MAX_BRACKET_DEPTH} deep", token)
            elif kind in CLOSING and brackets:
                brackets.pop()
            elif kind == "NAME" and token == "joint" and last is not None and last.type == "WITH":
                # `with joint "NAME" v` (docs/assets.md): a keyword right after `with` only.
                token = Token.new_borrow_pos("JOINT", token, token)
            yield token
            last = token
        if brackets:
            raise LayoutError(f"'{OPENING[brackets[-1].type]}' is never closed", brackets[-1])
        if last is not None and last.type != "_NL":
            end = Token("_NL", "\n", start_pos=last.end_pos, line=last.end_line, column=last.end_column,
                        end_line=last.end_line, end_column=last.end_column + 1, end_pos=last.end_pos)
            yield end
            last = end
        while len(indents) > 1:
            indents.pop()
            yield _indent_token("_DEDENT", last, 0)
