"""`--seed` and `--jobs` are checked in one place (prsc/pipeline/seed_jobs.py) and say the
same in every subcommand that takes them: exit 2, one line, nothing written."""

from __future__ import annotations

from pathlib import Path

import pytest

from prsc.cli import main

SPEC = str(Path(__file__).resolve().parents[2] / "specs" / "table_cube.prs")
COMMANDS = {
    "compile": ["compile", SPEC, "--target", "json"],
    "run": ["run", SPEC],
    "falsify": ["falsify", SPEC],
    "bench": ["bench", SPEC, "--backends"],
}


@pytest.mark.parametrize("command", sorted(COMMANDS))
@pytest.mark.parametrize("option, value, message", [("--seed", "-1", "--seed must be >= 0, got -1"),
                                                    ("--jobs", "0", "--jobs must be >= 1, got 0")])
def test_every_command_refuses_a_bad_seed_or_job_count_alike(command, option, value, message, tmp_path, capsys):
    out = tmp_path / "out"
    assert main([*COMMANDS[command], option, value, "-o", str(out)] if command != "bench"
                else [*COMMANDS[command], option, value]) == 2
    assert capsys.readouterr().err == f"prsc: error: {message}\n"
    assert not out.exists()
