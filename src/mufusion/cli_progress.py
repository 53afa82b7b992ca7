"""The command line's progress bar and its outcome table (printed in the terminal's width), and
the error exit every subcommand shares."""

from __future__ import annotations

from typing import NoReturn

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

console = Console(stderr=True)
"""Where the command line reports progress and errors (stderr)."""


def fail(message: str) -> NoReturn:
    """Print ``message`` as an error and exit with code 2 (bad input, before any work)."""
    console.print(f"[red]error:[/red] {message}")
    raise typer.Exit(code=2)


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
