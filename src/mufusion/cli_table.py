"""The outcome table on the terminal: the full layout where it fits, a compact one where not.

The full layout (boxed, the headers on one line) of a ``reproduce`` is 95 characters wide: an
80-column terminal wrapped it into three lines per cell. Narrower than the full table, the same
columns are printed without the box, each exactly as wide as its widest cell, the headers
wrapped at their spaces; one run stays one line. ``report.md`` keeps every column.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from rich.console import Console
from rich.measure import Measurement
from rich.table import Table

from mufusion.metrics.table import TABLE_COLUMNS, format_cell

TITLE = "outcome (full names and all metrics in summary.json)"
_GAP = 2  # characters between the compact layout's columns


def outcome_table(rows: Sequence[dict[str, Any]], width: int) -> Table:
    """The terminal's outcome table of ``rows`` (summary entries) for a ``width``-column screen.

    Returns the full layout if it fits in ``width``, else the compact one (no box, columns as
    wide as their widest cell, or their header where that still fits; else the headers wrap at
    their spaces).

    Examples
    --------
    >>> rows = [{"variant": "turn-authors", "config": "F-safe", "collision": False}]
    >>> outcome_table(rows, 120).box is None, outcome_table(rows, 20).box is None
    (False, True)
    """
    cols = [c for c in TABLE_COLUMNS if c.terminal and any(c.key in r for r in rows)]
    cells = [[format_cell(r.get(c.key), c) for c in cols] for r in rows]
    full = Table(title=TITLE)
    for col in cols:
        full.add_column(col.header, overflow="fold")
    for line in cells:
        full.add_row(*line)
    wide = Console(width=10_000)  # the natural width: a measurement is capped at the console's
    if Measurement.get(wide, wide.options, full).maximum <= width:
        return full
    widest = [max([len(line[i]) for line in cells] or [1]) for i in range(len(cols))]
    one_line = [max(w, len(col.header)) for w, col in zip(widest, cols, strict=True)]
    gaps = _GAP * (len(cols) - 1)
    wrapped = sum(one_line) + gaps > width  # headers on several lines, at their spaces
    compact = Table(title=TITLE, box=None, show_edge=False, pad_edge=False,
                    padding=(0, _GAP // 2), header_style="bold")
    for col, w, w_one in zip(cols, widest, one_line, strict=True):
        longest_word = max(len(word) for word in col.header.split())
        compact.add_column(col.header, min_width=w, overflow="fold",
                           max_width=max(w, longest_word) if wrapped else w_one)
    for line in cells:
        compact.add_row(*line)
    return compact


def print_outcome_table(rows: Sequence[dict[str, Any]], console: Console) -> None:
    """Print :func:`outcome_table` of ``rows`` on ``console``, laid out for its width."""
    console.print(outcome_table(rows, console.width))
