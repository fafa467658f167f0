"""Nothing the README used to hold is lost: each measurement table it had before it became a
front page (2026-11-27) is, header and rows, on a docs page the README links to."""

from __future__ import annotations

from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
README = (REPO / "README.md").read_text(encoding="utf-8")

# (page, the table's header, its first row) as the README had them.
TABLES = [
    ("docs/benchmarks.md", "| spec | sampler | scenes/s | rejections per scene | by cause | peak memory |",
     "| tableCube | **exact** (default law, batched) | **21,471** | **0** | none | 99 MB |"),
    ("docs/benchmarks.md", "| target | scenes/s, 1 job | scenes/s, 2 jobs | files/s, 2 jobs |",
     "| json | 2,079 | 2,359 | 2,359 |"),
    ("docs/case-study.md", "| outcome | prsc (MuJoCo) | paper (CoppeliaSim) |", "| success | 77 | 74 |"),
    ("docs/falsify.md", "| | failed episodes of 200 | per 100 | weighted failure probability (95 % CI) |",
     "| `--method uniform` | 41 (19 perception, 21 poor grip, 1 no path) | 20.5 | 0.205 (raw) |"),
    ("docs/examples.md", "| spec | shows |", None),
    ("docs/cli.md", "| command | what it does |", None),
]


@pytest.mark.parametrize("page, header, row", TABLES, ids=[t[1][:30] for t in TABLES])
def test_the_table_is_on_a_page_the_readme_links_to(page, header, row):
    text = (REPO / page).read_text(encoding="utf-8")
    assert header in text
    assert row is None or row in text
    assert f"]({page})" in README
