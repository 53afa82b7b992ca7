"""mufusion.plots: figures, read from run logs only (never the live loop)."""

from mufusion.plots.animation import animate_run
from mufusion.plots.estimate import plot_fused_estimate
from mufusion.plots.forces import force_polygon_vertices, plot_planned_forces
from mufusion.plots.snapshots import plot_snapshots
from mufusion.plots.traces import plot_lateral_and_speed

__all__ = [
    "animate_run",
    "force_polygon_vertices",
    "plot_fused_estimate",
    "plot_lateral_and_speed",
    "plot_planned_forces",
    "plot_snapshots",
]
