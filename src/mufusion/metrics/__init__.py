"""Per-run metrics computed from run logs, and the outcome table's columns."""

from mufusion.metrics.run_metrics import RunMetrics, attach_gt_comparison, compute_metrics
from mufusion.metrics.table import TABLE_COLUMNS, TableColumn, format_cell

__all__ = [
    "TABLE_COLUMNS",
    "RunMetrics",
    "TableColumn",
    "attach_gt_comparison",
    "compute_metrics",
    "format_cell",
]
