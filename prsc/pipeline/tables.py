"""Summary tables on standard output: the title on a line of its own, never wrapped.

rich wraps a table's title to the table's width, so a long title over a narrow table broke
mid-line, on a terminal and in a pipe alike."""

from __future__ import annotations

from typing import Any


def print_table(table: Any, console: Any = None) -> None:
    """Print a rich Table's title as one unwrapped line, then the table without it."""
    from rich.console import Console

    console = console or Console()
    title, table.title = table.title, None
    if title:
        console.print(str(title), soft_wrap=True, highlight=False, markup=False)
    console.print(table)
