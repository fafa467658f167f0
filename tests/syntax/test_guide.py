"""Every ```prs example in docs/language.md compiles."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from prsc.ir import compile_program

GUIDE = Path(__file__).resolve().parents[2] / "docs" / "language.md"
BLOCKS = re.findall(r"```prs\n(.*?)```", GUIDE.read_text(), re.S)


def test_the_guide_has_examples():
    assert len(BLOCKS) >= 20


@pytest.mark.parametrize("index", range(len(BLOCKS)))
def test_guide_example_compiles(tmp_path, index):
    spec = tmp_path / f"example_{index}.prs"
    spec.write_text(BLOCKS[index])
    program = compile_program(str(spec))
    assert program.objects or program.variables
