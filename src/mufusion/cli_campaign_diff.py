"""``mufusion campaign-diff``: two campaigns of the same grid compared run by run.

A thin layer over :func:`mufusion.campaign.diff.campaign_diff`: the directories are read (exit 2
naming the one that holds no campaign, or when the two share no run), the outcome counts that
changed and the runs that flipped are printed, the whole comparison written as Markdown with
``--out``; ``--fail-on-worse`` exits 1 where any outcome got worse (a gate for a user's CI).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from mufusion.cli_progress import console
from mufusion.cli_progress import fail as _fail

# Flipped runs printed on the terminal; all of them are in the Markdown (--out).
MAX_FLIPS_SHOWN = 20


def campaign_diff(
    before: Annotated[Path, typer.Argument(help="Output directory of the first campaign.")],
    after: Annotated[Path, typer.Argument(help="Output directory of the second campaign.")],
    out: Annotated[
        Path | None, typer.Option("--out", "-o", help="Write the comparison as Markdown here.")
    ] = None,
    fail_on_worse: Annotated[
        bool, typer.Option(help="Exit 1 if any run's outcome got worse (collision, out of lane, "
                           "off the road, spun).")
    ] = False,
) -> None:
    """Compare two campaigns of the same grid run by run: outcome counts per configuration and
    oracle class, every run whose outcome flipped, how far the graded outcomes moved."""
    from mufusion.campaign.diff import campaign_diff as compare
    from mufusion.campaign.diff import diff_markdown
    from mufusion.campaign.report import load_campaign_results

    try:
        first, second = load_campaign_results(before), load_campaign_results(after)
        diff = compare(first.table, second.table)
    except ValueError as err:
        _fail(str(err))
    console.print(f"{diff.matched} runs in both; {diff.only_before} only in {str(before)!r}, "
                  f"{diff.only_after} only in {str(after)!r}")
    changed = diff.counts[diff.counts["before"] != diff.counts["after"]]
    if changed.empty:
        console.print("every outcome count per configuration and class is the same")
    else:
        table = Table("config", "class", "outcome", "runs", "before", "after",
                      title="outcome counts that changed")
        for r in changed.to_dict("records"):
            table.add_row(*(str(r[c]) for c in ("config", "class", "outcome", "runs", "before",
                                                "after")))
        console.print(table)
    for r in diff.flips.head(MAX_FLIPS_SHOWN).to_dict("records"):
        console.print(f"  {r['config']} {r['class']} {r['outcome']} {r['before']} → "
                      f"{r['after']}: {escape(str(r['variant']))} (seed {r['seed']})")
    if len(diff.flips) > MAX_FLIPS_SHOWN:
        console.print(f"  … {len(diff.flips) - MAX_FLIPS_SHOWN} more (all of them with --out)")
    if out is not None:
        try:
            out.write_text(diff_markdown(diff, str(before), str(after)))
        except OSError as err:
            _fail(f"--out {str(out)!r} is not writable: {err}")
        console.print(f"comparison: [bold]{out}[/bold]")
    if fail_on_worse and diff.worse:
        console.print(f"[red]{diff.worse} outcome(s) got worse[/red]")
        raise typer.Exit(code=1)
