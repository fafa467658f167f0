"""Nothing is Panda-specific below the model library (issue 40): the built-in Panda is the
library's data (prsc/library/panda.json, tabletop.prs) read by the asset path every arm takes,
so no module of prsc/, backends/ or assets/ names it. The word "pandas" (the data-frame
library lerobot's parquet metadata names) is not the arm."""

from __future__ import annotations

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PANDA = re.compile(r"panda(?!s)", re.IGNORECASE)
ALLOWED = {"prsc/library"}  # the model library: the class and the data naming the file


def _named(repo: Path = REPO) -> list[str]:
    found = []
    for folder in ("prsc", "backends", "assets"):
        for path in sorted((repo / folder).rglob("*")):
            relative = path.relative_to(repo).as_posix()
            if not path.is_file() or path.suffix == ".pyc" or any(relative.startswith(a + "/") for a in ALLOWED):
                continue
            for number, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
                if PANDA.search(line) or PANDA.search(path.name):
                    found.append(f"{relative}:{number}: {line.strip()}")
    return found


def test_no_module_below_the_library_names_the_panda():
    assert _named() == []


def test_the_rule_finds_a_panda(tmp_path):
    """The scan can fail: a module naming the arm is found, one naming pandas is not."""
    (tmp_path / "prsc" / "x").mkdir(parents=True)
    (tmp_path / "prsc" / "x" / "a.py").write_text("import pandas\nARM = 'Panda'\n", encoding="utf-8")
    for folder in ("backends", "assets", "prsc/library"):
        (tmp_path / folder).mkdir(parents=True, exist_ok=True)
    (tmp_path / "prsc" / "library" / "panda.json").write_text("{}", encoding="utf-8")
    assert _named(tmp_path) == ["prsc/x/a.py:2: ARM = 'Panda'"]
