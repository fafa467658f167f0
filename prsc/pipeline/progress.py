"""A progress bar for long commands (compile, sample, run), shown only on a terminal: never
in logs or pipes. It shows the count, the rate (scenes or episodes per second) and the ETA."""

from __future__ import annotations

import sys


def progress_bar(total: int, label: str = "compiling", unit: str = "scenes"):
    """A rich progress bar on stderr when it is a terminal, or None."""
    if total == 0 or not sys.stderr.isatty():
        return None
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, ProgressColumn, TextColumn, TimeRemainingColumn
    from rich.text import Text

    class RateColumn(ProgressColumn):
        """Items per second, once rich has measured it."""

        def render(self, task) -> Text:
            speed = task.finished_speed or task.speed
            return Text(f"{speed:,.1f} {unit}/s" if speed else f"- {unit}/s")

    return Progress(TextColumn(label), BarColumn(), MofNCompleteColumn(), RateColumn(), TimeRemainingColumn(),
                    console=Console(file=sys.stderr), transient=True)
