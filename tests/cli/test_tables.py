"""Summary tables printed by run and falsify."""

from __future__ import annotations


def test_a_long_table_title_stays_on_one_line_in_a_pipe():
    """Issue 23: the summary table's title wrapped mid-line when piped (rich fits it to the table)."""
    import io

    from rich.console import Console
    from rich.table import Table

    from prsc.pipeline.tables import print_table

    title = "table_cube.prs: 100 episodes of handover (seed 0), outcome per scene, in a pipe"
    table = Table(title=title)
    table.add_column("outcome")
    table.add_row("success")
    stream = io.StringIO()
    print_table(table, Console(file=stream, width=40))
    lines = stream.getvalue().splitlines()
    assert lines[0] == title and "success" in stream.getvalue()
