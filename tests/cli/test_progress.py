"""Long commands show a progress bar with the rate and the ETA on a terminal, and nothing
when their output is piped or logged."""

from __future__ import annotations

import os
import pty
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SPEC = str(REPO / "specs" / "table_cube.prs")


def _sample(stderr) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "prsc.cli", "sample", SPEC, "-n", "400", "--law", "sequential"],
                          stdout=subprocess.PIPE, stderr=stderr, timeout=300,
                          env={**os.environ, "COLUMNS": "120", "TERM": "xterm"})


def test_sample_shows_scenes_per_second_on_a_terminal_only():
    main, child = pty.openpty()
    try:
        done = _sample(child)
        os.close(child)
        shown = b""
        while True:
            try:
                chunk = os.read(main, 65536)
            except OSError:
                break
            if not chunk:
                break
            shown += chunk
    finally:
        os.close(main)
    assert done.returncode == 0
    assert b"scenes/s" in shown and b"/400" in shown
    assert len(done.stdout.splitlines()) == 400  # the scenes themselves still go to stdout
    piped = _sample(subprocess.PIPE)
    assert piped.returncode == 0 and b"scenes/s" not in piped.stderr
