"""A progress bar for long commands, shown only on a terminal (never in logs or pipes)."""

from __future__ import annotations

import sys


def progress_bar(total: int, label: str = "compiling"):
    """A rich progress bar on stderr when it is a terminal, or None."""
    if total == 0 or not sys.stderr.isatty():
        return None
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    return Progress(TextColumn(label), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn(),
                    console=Console(file=sys.stderr), transient=True)
