"""The command line's progress bar, its outcome table (printed in the terminal's width), the
fixed list of runs `reproduce` makes under that bar, and the error exit every subcommand shares."""

from __future__ import annotations

import json
from pathlib import Path
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


def run_specs(specs: list, out: Path, jobs: int | None,
              console: Console) -> tuple[list, list[dict]]:
    """Run ``specs`` under a progress bar; their ``(spec, metrics, directory)`` results and
    their ``runs`` entries for ``summary.json``.

    Failed runs end the command with exit 1 naming them (the others are saved), as a campaign
    with failed runs does. Ctrl-C or
    SIGTERM ends it with 128 + the signal's number, after writing ``out/summary.json`` with the
    runs that finished (``"partial": true``, the count ``pending``, ``interrupted_by``): a
    preempted ``reproduce`` leaves what it ran and says so instead of a traceback.
    """
    from mufusion.campaign import CampaignInterrupted, run_campaign

    with progress_bar(console) as progress:
        task = progress.add_task("runs", total=len(specs))
        try:
            results = run_campaign(
                specs, out / "runs", jobs=jobs, on_done=lambda _s: progress.advance(task)
            )
        except RuntimeError as err:  # some runs failed; the others are saved
            console.print(f"[red]error:[/red] {err}")
            raise typer.Exit(code=1) from None
        except CampaignInterrupted as stop:
            done = [(r.spec, r.metrics, r.directory) for r in stop.finished
                    if r.metrics is not None and r.directory is not None]
            summary = {"runs": _entries(done), "partial": True, "pending": len(stop.pending),
                       "interrupted_by": stop.signal.name}
            (out / "summary.json").write_text(json.dumps(summary, indent=2))
            console.print(
                f"[yellow]interrupted ({stop.signal.name}):[/yellow] {len(stop.pending)} runs "
                f"did not run; the {len(done)} that finished are in {out / 'summary.json'} "
                "(marked partial). Run the command again for the whole reproduction."
            )
            raise typer.Exit(code=128 + stop.signal.value) from None
    return results, _entries(results)


def _entries(results: list) -> list[dict]:
    return [
        {"scenario": s.scenario, "variant": s.variant, "config": s.config, "log": str(d),
         **m.to_dict()}
        for s, m, d in results
    ]
