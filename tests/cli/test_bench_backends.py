"""`prsc bench --backends` and `make bench` work from a clone alone (issue 12, item 10)."""

from __future__ import annotations

import re
from pathlib import Path

from prsc.cli import main

REPO = Path(__file__).resolve().parents[2]


def test_bench_backends_prints_a_row_per_target_and_job_count(capsys):
    assert main(["bench", "--backends", str(REPO / "specs" / "table_cube.prs"), "-n", "2", "--jobs", "1,2",
                 "--target", "json"]) == 0
    rows = [line.split() for line in capsys.readouterr().out.splitlines() if line.startswith("json ")]
    assert [(r[0], r[1], r[4]) for r in rows] == [("json", "1", "2"), ("json", "2", "2")]


def test_bench_backends_refuses_bad_options(capsys):
    spec = str(REPO / "specs" / "table_cube.prs")
    assert main(["bench", "--backends", spec, "--jobs", "0"]) == 2
    assert main(["bench", "--backends", spec, "--target", "obj"]) == 2
    assert "unknown target obj" in capsys.readouterr().err


def test_make_bench_and_the_readme_read_only_the_repository():
    """Every spec `make bench` and the bench commands of the README and docs/benchmarks.md name is in the repository."""
    makefile = (REPO / "Makefile").read_text()
    recipe = makefile[makefile.index("\nbench:"):].split("\n\n")[0]
    specs_line = next(line for line in makefile.splitlines() if line.startswith("BENCH_SPECS"))
    required = specs_line + recipe
    readme = (REPO / "README.md").read_text() + (REPO / "docs" / "benchmarks.md").read_text()
    commands = " ".join(re.findall(r"`(prsc bench[^`]*)`", readme))
    assert "prsc bench specs/table_cube.prs" in commands
    assert "../shared" not in makefile + readme
    for text in (required, commands):
        for path in re.findall(r"\S+\.prs", text):
            assert (REPO / path).is_file(), path
    assert "prsc.backends.bench" not in makefile + readme


def test_bench_episodes_reports_cpu_per_episode_and_where_it_goes(capsys):
    """`prsc bench --episodes` (the last line of `make bench`) runs real episodes and splits their cost."""
    assert main(["bench", "--episodes", str(REPO / "specs" / "table_cube.prs"), "-n", "2"]) == 0
    out = capsys.readouterr().out
    per_episode = re.search(r"([\d.]+) CPU s per episode = ([\d.]+) episodes per CPU-second", out)
    assert per_episode and float(per_episode.group(1)) > 0
    assert abs(float(per_episode.group(1)) * float(per_episode.group(2)) - 1) < 0.01
    assert re.search(r"load [\d.]+, mj_step [\d.]+ .* render [\d.]+", out) and "outcomes: " in out
    # the split counts the timed episode only (the task's paired runs are untimed): nothing is counted twice
    rest = re.search(r"controller and the rest (-?[\d.]+) CPU s", out)
    assert rest and float(rest.group(1)) >= 0
    # the handover states a task: its cost as the median of per-scene ratios, and their quartiles
    assert re.search(r"per scene, median [+-][\d.]+% \(quartiles [+-][\d.]+% to [+-][\d.]+%, n=1\)", out)
    assert main(["bench", "--episodes", str(REPO / "specs" / "table_cube.prs"), "-n", "1"]) == 2
