"""Mutated specs (token deletions, swaps, random bytes) never crash `prsc check`."""

from __future__ import annotations

import re
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from prsc.cli import main
from tests.original import original_paths

REPO = Path(__file__).resolve().parents[2]
SOURCES = [p.read_bytes() for p in original_paths() + sorted((REPO / "specs").glob("*.prs"))]
TOKENS = re.compile(rb"\w+|\s+|.", re.S)
SNIPPETS = [b"(", b")", b",", b"\n", b"    ", b"deg", b"on", b"left", b"top", b"with", b"self", b"[", b"{", b":",
            b"=", b"class", b'"', b"require", b"(1, 2)", b"Vector3D", b"import", b"math", b".x", b"\t", b"\\"]
ERROR_LINE = re.compile(r"^\S.*:\d+:\d+: error: ", re.M)

mutation = st.one_of(
    st.tuples(st.just("delete"), st.integers(0, 10**6)),
    st.tuples(st.just("swap"), st.integers(0, 10**6), st.integers(0, 10**6)),
    st.tuples(st.just("bytes"), st.integers(0, 10**6), st.binary(min_size=1, max_size=4)),
    st.tuples(st.just("snippet"), st.integers(0, 10**6), st.sampled_from(SNIPPETS)),
    st.tuples(st.just("duplicate"), st.integers(0, 10**6), st.integers(0, 10**6)),
)


def mutate(source: bytes, mutations) -> bytes:
    """Apply token-level mutations to a spec."""
    parts = TOKENS.findall(source)
    for m in mutations:
        if not parts:
            break
        k = m[1] % len(parts)
        if m[0] == "delete":
            del parts[k]
        elif m[0] == "swap":
            j = m[2] % len(parts)
            parts[k], parts[j] = parts[j], parts[k]
        elif m[0] == "bytes":
            parts.insert(k, m[2])
        elif m[0] == "snippet":
            parts[k] = m[2]
        else:
            parts.insert(k, parts[m[2] % len(parts)])
    return b"".join(parts)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(index=st.integers(0, len(SOURCES) - 1), mutations=st.lists(mutation, min_size=1, max_size=4))
def test_mutants_exit_cleanly(tmp_path, capsys, index, mutations):
    spec = tmp_path / "mutant.prs"
    spec.write_bytes(mutate(SOURCES[index], mutations))
    capsys.readouterr()
    code = main(["check", "-q", str(spec)])
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert code in (0, 2)
    if code == 2:
        assert ERROR_LINE.search(err), err


def test_garbage_inputs(tmp_path, capsys):
    cases = {
        "binary.prs": bytes(range(256)) * 4,
        "nul.prs": b"x = 1\x00\n",
        "empty.prs": b"",
        "huge.prs": b"x = 1\n" * (10 * 1024 * 1024 // 6),
        "deep_parens.prs": b"x = " + b"(" * 5000 + b"1" + b")" * 5000 + b"\n",
        "deep_unary.prs": b"x = " + b"-" * 20000 + b"1\n",
        "deep_not.prs": b"x = " + b"not " * 5000 + b"True\n",
        "long_sum.prs": b"x = " + b"+".join([b"1"] * 20000) + b"\n",
        "lone_cr.prs": b"x = 1\ry = 2\n",
        "bom.prs": b"\xef\xbb\xbfx = \n",
    }
    for name, data in cases.items():
        spec = tmp_path / name
        spec.write_bytes(data)
        code = main(["check", "-q", str(spec)])
        err = capsys.readouterr().err
        assert code == 2, name
        assert ERROR_LINE.search(err), (name, err)
