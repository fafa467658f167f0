"""Every command's --help ends with one example line, and the example is a valid command line."""

from __future__ import annotations

import contextlib
import io
import shlex
from pathlib import Path

import pytest

from prsc.cli import COMMANDS, EXAMPLES, build_parser

REPO = Path(__file__).resolve().parents[2]


def _help(name: str) -> str:
    out = io.StringIO()
    with contextlib.redirect_stdout(out), pytest.raises(SystemExit):
        build_parser(name).parse_args([name, "--help"])
    return out.getvalue()


@pytest.mark.parametrize("name", COMMANDS)
def test_help_ends_with_an_example_that_parses(name):
    last = _help(name).rstrip("\n").splitlines()[-1]
    assert last == f"example: {EXAMPLES[name]}"
    words = shlex.split(EXAMPLES[name].replace('"$PYBULLET_DATA"', "data"))
    assert words[:2] == ["prsc", name]
    args = build_parser(name).parse_args(words[1:])
    assert args.command == name
    specs = [w for w in words if w.endswith(".prs")]
    assert all((REPO / w).is_file() for w in specs), specs
