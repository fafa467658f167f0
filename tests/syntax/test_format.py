"""The AST dump of `prsc explain --stage syntax`: every node with its line:col, children indented."""

from __future__ import annotations

from prsc.syntax import parse_source
from prsc.syntax.ast_text import format_ast


def test_nodes_fields_and_spans():
    text = format_ast(parse_source("tr_1 = Tray completely on t, left of (top t) by 0.2\n", "t.prs"))
    assert text == (
        "Module 1:1 path='t.prs'\n"
        "  statements:\n"
        "    - ObjectStmt 1:1 name='tr_1' class_name='Tray'\n"
        "      specifiers:\n"
        "        - OnSpec 1:13 completely=True\n"
        "          target: Name 1:27 id='t'\n"
        "        - DirectionSpec 1:30 relation='left'\n"
        "          target: FacePoint 1:38 words=('top',) words_closed=True\n"
        "            target: Name 1:43 id='t'\n"
        "          by: Number 1:49 value=0.2\n"
    )


def test_lists_of_pairs_and_empty_fields():
    """Dict items and comparison chains are tuples of tuples; an empty argument list stays inline."""
    text = format_ast(parse_source("d = Discrete({1: 0.5})\nrequire 1 < f()\n", "t.prs"))
    assert text == (
        "Module 1:1 path='t.prs'\n"
        "  statements:\n"
        "    - Assign 1:1 target='d'\n"
        "      value: Call 1:5\n"
        "        func: Name 1:5 id='Discrete'\n"
        "        args:\n"
        "          - DictLit 1:14\n"
        "            items:\n"
        "              -\n"
        "                - Number 1:15 value=1.0\n"
        "                - Number 1:18 value=0.5\n"
        "    - RequireStmt 2:1 probability=None\n"
        "      condition: Compare 2:9\n"
        "        left: Number 2:9 value=1.0\n"
        "        rest:\n"
        "          -\n"
        "            - '<'\n"
        "            - Call 2:13 args=()\n"
        "              func: Name 2:13 id='f'\n"
    )
