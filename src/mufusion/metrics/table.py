"""The outcome table's columns, defined once for the CLI's summary and the reports."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

CellFormat = Literal["text", "yes/no", "number", "percent", "cm"]


@dataclass(frozen=True)
class TableColumn:
    """One column: the summary key it shows, a short header and how to format it."""

    key: str
    header: str
    format: CellFormat = "number"
    terminal: bool = True
    """Also in the terminal's table (kept readable at 80 columns); reports show every column."""


TABLE_COLUMNS: tuple[TableColumn, ...] = (
    TableColumn("scenario", "scenario", "text", terminal=False),
    TableColumn("variant", "variant", "text"),
    TableColumn("config", "cfg", "text"),
    TableColumn("feasibility", "physics", "text", terminal=False),
    TableColumn("collision", "crash", "yes/no"),
    TableColumn("impact_speed_mps", "hit m/s"),
    TableColumn("min_clearance_m", "clear m"),
    TableColumn("max_lane_excursion_m", "out cm", "cm"),
    TableColumn("time_outside_lane_s", "out s"),
    TableColumn("max_opposing_lane_depth_m", "opp cm", "cm"),
    TableColumn("spun", "spun", "yes/no", terminal=False),
    TableColumn("utilization_vs_gt", "util vs GT %", "percent"),
    TableColumn("max_force_excess", "F excess %", "percent", terminal=False),
    TableColumn("min_time_to_collision_s", "TTC s", terminal=False),
    TableColumn("max_required_decel_over_mu_g", "a_req/μg", terminal=False),
    TableColumn("fallbacks", "fallbacks", "number", terminal=False),
)
"""Columns of the outcome table (summary.json has the full names and every metric)."""


def format_cell(value: Any, column: TableColumn) -> str:
    """A summary value as table text: — for none, yes/no, signed percent, centimetres, 3 digits.

    Examples
    --------
    >>> format_cell(-0.326, TableColumn("utilization_vs_gt", "util", "percent"))
    '-32.6'
    >>> format_cell(0.1234, TableColumn("max_lane_excursion_m", "exc", "cm"))
    '12.3'
    """
    if value is None:
        return "–"
    if column.format == "yes/no" or isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int | float) and column.format == "percent":
        return f"{100 * value:+.1f}"
    if isinstance(value, int | float) and column.format == "cm":
        return f"{100 * value:.1f}"
    if isinstance(value, float):
        return f"{value:.3g}"
    return str(value)
