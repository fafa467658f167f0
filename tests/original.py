"""The original project's specs: beside the repository in CI (`../shared/specs/original`),
absent from a user's clone. Tests that read them skip, with this reason, when they are absent.

PRSC_ORIGINAL_SPECS points elsewhere (a missing folder simulates a bare clone).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
ORIGINAL = Path(os.environ.get("PRSC_ORIGINAL_SPECS", REPO / ".." / "shared" / "specs" / "original"))
PRESENT = (ORIGINAL / "tableCube.prs").is_file()
REASON = f"the original specs are not beside this clone ({ORIGINAL} is missing)"

needs_original = pytest.mark.skipif(not PRESENT, reason=REASON)
"""Mark a test that reads ORIGINAL: skipped, with the reason, in a bare clone."""


def original_paths() -> list[Path]:
    """The original specs, or none in a bare clone."""
    return sorted(ORIGINAL.glob("*.prs")) if PRESENT else []


def original_params(as_text: bool = False) -> list:
    """Parameters for the original specs (paths, or their text with `as_text`); in a bare
    clone one visibly skipped parameter."""
    if PRESENT:
        return [str(p) if as_text else p for p in original_paths()]
    absent = ORIGINAL / "absent.prs"
    return [pytest.param(str(absent) if as_text else absent, marks=pytest.mark.skip(reason=REASON), id="original-specs")]
