"""The command line's progress bar and its outcome table (printed in the terminal's width)."""

from __future__ import annotations

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn


def progress_bar(console: Console) -> Progress:
    """A progress bar of runs (or simulated seconds) with the elapsed time, on ``console``."""
    return Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        TextColumn("{task.completed:.1f}/{task.total:.1f}"),
        TimeElapsedColumn(),
        console=console,
    )


def print_table(rows: list[dict]) -> None:
    """The outcome table of ``rows`` (summary entries); imported when first printed, as its
    metrics' column definitions are."""
    from mufusion.cli_table import print_outcome_table

    print_outcome_table(rows, Console())
