"""Per-run metrics computed from run logs."""

from mufusion.metrics.run_metrics import RunMetrics, attach_gt_comparison, compute_metrics

__all__ = ["RunMetrics", "attach_gt_comparison", "compute_metrics"]
