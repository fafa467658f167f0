"""Seeded mutants of specs/*.prs through the whole pipeline (issue 12): `compile` exits 0 or 2,
never prints a traceback, every error names a `path:line:col` inside the file it names, and a
failed compile leaves no files. Most mutants run in process; a handful through the real CLI."""

from __future__ import annotations

import os
import random
import re
import subprocess
import sys
from pathlib import Path

import pytest

from prsc.cli import main
from tests.cli.test_check_fuzz import SNIPPETS, mutate

REPO = Path(__file__).resolve().parents[2]
SOURCES = [p.read_bytes() for p in sorted((REPO / "specs").glob("*.prs"))]
# Values the hostile campaign found crashing or misplaced, on top of the syntax snippets.
HOSTILE = [b"with width 0", b'with mesh "/etc/passwd"', b'with shape "mesh"', b"..", b"- - - -"]
HOSTILE_NUMBERS = [b"0", b"-1", b"1e-300", b"1e300", b"(0, 1e-9)", b"1e400", b"0.0000001"]
HOSTILE_NAMES = [b"world", b"self", b"Object", b"workspace", b"_", b"x1"]
NUMBER = re.compile(rb"(?<![\w.])\d+(\.\d+)?(?![\w.])")
NAME = re.compile(rb"(?<![\w.])[A-Za-z_]\w*")
LOCATION = re.compile(r"^(?P<path>\S.*?):(?P<line>\d+):(?P<col>\d+): error: ", re.M)
INPUTS = 200
MUTATIONS = ("delete", "swap", "bytes", "snippet", "duplicate")


def _mutant(rng: random.Random) -> bytes:
    """A spec with 1-3 mutations drawn from `rng`: a number or name replaced by a hostile
    value, or a token-level mutation as test_check_fuzz applies (printable bytes mostly)."""
    source = rng.choice(SOURCES)
    for _ in range(rng.randint(1, 3)):
        if rng.random() < 0.4:
            numbers = list(NUMBER.finditer(source))
            names = list(NAME.finditer(source))
            if rng.random() < 0.7 and numbers:
                found, value = rng.choice(numbers), rng.choice(HOSTILE_NUMBERS)
            elif names:
                found, value = rng.choice(names), rng.choice(HOSTILE_NAMES)
            else:
                continue
            source = source[:found.start()] + value + source[found.end():]
            continue
        kind = rng.choice(MUTATIONS)
        k = rng.randrange(10**6)
        if kind in ("swap", "duplicate"):
            mutation = (kind, k, rng.randrange(10**6))
        elif kind == "bytes":
            alphabet = range(256) if rng.random() < 0.1 else range(32, 127)
            mutation = (kind, k, bytes(rng.choice(alphabet) for _ in range(rng.randint(1, 3))))
        else:
            mutation = (kind, k, rng.choice(SNIPPETS + HOSTILE))
        source = mutate(source, [mutation])
    return source


def _check_report(code: int, err: str, out: Path) -> None:
    assert code in (0, 2), err
    assert "Traceback" not in err and "internal error" not in err, err
    if code == 0:
        return
    assert not out.exists(), f"a failed compile left {sorted(out.rglob('*'))}"
    found = LOCATION.search(err)
    if found is None:
        assert err.startswith("prsc: error: "), err  # an error of the run, not of a place in a file
        return
    path, line, col = found["path"], int(found["line"]), int(found["col"])
    lines = Path(path).read_bytes().split(b"\n")
    assert 1 <= line <= len(lines), err
    assert 1 <= col <= len(lines[line - 1]) + 2, err


def test_mutants_compile_or_fail_cleanly(tmp_path, capsys):
    rng = random.Random(12)
    codes = []
    for k in range(INPUTS):
        folder = tmp_path / str(k)
        folder.mkdir()
        spec = folder / "mutant.prs"
        spec.write_bytes(_mutant(rng))
        out = folder / "out"
        code = main(["compile", str(spec), "--target", "json", "-o", str(out), "-I", str(REPO / "specs")])
        _check_report(code, capsys.readouterr().err, out)
        codes.append(code)
    # The mutants exercise both paths: some still compile, most are errors.
    assert 0 < codes.count(0) < INPUTS and codes.count(2) > INPUTS // 3


@pytest.mark.parametrize("seed", range(4))
def test_mutants_through_the_real_cli(tmp_path, seed):
    rng = random.Random(1000 + seed)
    spec = tmp_path / "mutant.prs"
    spec.write_bytes(_mutant(rng))
    out = tmp_path / "out"
    run = subprocess.run([sys.executable, "-m", "prsc.cli", "compile", str(spec), "--target", "json,mjcf",
                          "-o", str(out), "-I", str(REPO / "specs")],
                         capture_output=True, text=True, cwd=tmp_path, env=dict(os.environ, PYTHONPATH=str(REPO)))
    _check_report(run.returncode, run.stderr, out)
