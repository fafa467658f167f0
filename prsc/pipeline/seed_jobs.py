"""The `--seed` and `--jobs` of every subcommand that draws scenes or forks workers, checked
in one place so each says the same (prsc compile, run, falsify, bench)."""

from __future__ import annotations

from typing import Iterable

from prsc.errors import PrscError


def check_seed_and_jobs(seed: int, jobs: int | Iterable[int] = 1) -> None:
    """A PrscError for a negative seed or a job count below 1 (each of `jobs` when several)."""
    if seed < 0:
        raise PrscError(f"--seed must be >= 0, got {seed}")
    for count in [jobs] if isinstance(jobs, int) else jobs:
        if count < 1:
            raise PrscError(f"--jobs must be >= 1, got {count}")
