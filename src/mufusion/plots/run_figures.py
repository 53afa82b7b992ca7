"""Figure sets for one run (``mufusion run``) and for the reproduction (``mufusion reproduce``).

Which runs go side by side and at which positions is part of each
:class:`~mufusion.reproduction.variants.Variant` (paper Fig. 3: L vs F at s = 0, 15, 30, 55 m;
Fig. 4: P vs F at s = 0, 2, 18, 40 m).
"""

from __future__ import annotations

import math
import signal
from collections.abc import Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from itertools import repeat
from pathlib import Path

from mufusion.configurations import Configuration
from mufusion.plots.animation import animate_run
from mufusion.plots.estimate import plot_fused_estimate
from mufusion.plots.forces import plot_planned_forces
from mufusion.plots.slide import plot_slide
from mufusion.plots.snapshots import plot_snapshots
from mufusion.plots.traces import plot_lateral_and_speed
from mufusion.reproduction.variants import Variant, default_variant, variant
from mufusion.sim.log import RunLog, load_run


def _reachable_positions(log: RunLog, positions: Sequence[float]) -> list[float]:
    ts = log.timeseries
    travelled = float(ts["s_m"].iloc[-1]) - log.meta.start_s_m
    return [p for p in positions if p <= travelled]


SNAPSHOTS_PER_RUN = 4
"""Top views of a run without a paper layout (a ``road``): the start and three more, evenly
along the distance it travelled."""


def _snapshot_positions(log: RunLog) -> Sequence[float]:
    layout = default_variant(log.meta.scenario_name)
    if layout is not None:
        return layout.snapshot_positions_m
    travelled = float(log.timeseries["s_m"].iloc[-1]) - log.meta.start_s_m
    # Rounded down to a decimetre: the last one stays within the distance travelled.
    return [math.floor(10.0 * travelled * k / (SNAPSHOTS_PER_RUN - 1)) / 10.0
            for k in range(SNAPSHOTS_PER_RUN)]


def single_run_figures(log: RunLog, out_dir: Path, *, gif: bool = True) -> dict[str, Path]:
    """Figures of one run: snapshots, lateral offset and speed, planned forces, the estimate."""
    out_dir.mkdir(parents=True, exist_ok=True)
    t_c = log.meta.comparison_time_s
    figures: dict[str, Path] = {}
    positions = _reachable_positions(log, _snapshot_positions(log))
    if positions:
        figures["snapshots"] = plot_snapshots([log], positions, out_dir / "snapshots.png")
    figures["traces"] = plot_lateral_and_speed([log], out_dir / "lateral_speed.png")
    figures["forces"] = plot_planned_forces([log], t_c, out_dir / "planned_forces.png")
    if not log.estimates.empty and log.estimates["mean"].notna().any():
        figures["estimate"] = plot_fused_estimate(log, t_c, out_dir / "fused_estimate.png")
    if gif:
        figures["animation"] = animate_run(log, out_dir / "run.gif")
    return figures


def variant_figures(
    var: Variant, logs: Mapping[Configuration, RunLog], out_dir: Path, *, gif: bool = True
) -> dict[str, Path]:
    """The figures of one reproduction variant, keyed ``"<variant key>/<kind>"``."""
    tag = var.key
    t_c = next(iter(logs.values())).meta.comparison_time_s
    ordered = [logs[c] for c in Configuration if c in logs]
    pair_configs = [c for c in (var.contrast, Configuration.F) if c in logs]
    figures: dict[str, Path] = {}
    if pair_configs:
        pair = [logs[c] for c in pair_configs]
        positions = _reachable_positions(pair[-1], var.snapshot_positions_m)
        if positions:
            figures[f"{tag}/snapshots"] = plot_snapshots(
                pair, positions, out_dir / f"{tag}-snapshots.png"
            )
    figures[f"{tag}/traces"] = plot_lateral_and_speed(ordered, out_dir / f"{tag}-lateral_speed.png")
    figures[f"{tag}/forces"] = plot_planned_forces(
        ordered, t_c, out_dir / f"{tag}-planned_forces.png"
    )
    if Configuration.F in logs:
        figures[f"{tag}/estimate"] = plot_fused_estimate(
            logs[Configuration.F], t_c, out_dir / f"{tag}-fused_estimate.png"
        )
    # The turn's slide mechanism (paper Sec. IV-C): L, with GT and F for reference.
    slide_configs = (Configuration.L, Configuration.F, Configuration.GT)
    if var.scenario == "turn" and Configuration.L in logs:
        figures[f"{tag}/slide"] = plot_slide(
            [logs[c] for c in slide_configs if c in logs], out_dir / f"{tag}-slide.png",
            title=f"{var.title}: the slide mechanism",
        )
    if gif and var.animate:
        for config in pair_configs:
            figures[f"{tag}/{config.value}/animation"] = animate_run(
                logs[config], out_dir / f"{tag}-{config.value}.gif"
            )
    return figures


def _leave_interrupts() -> None:
    """A figure worker leaves Ctrl-C to the command, which stops after the figures under way
    (the workers would each print a traceback)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _variant_figures_from_runs(
    key: str, run_dirs: Mapping[str, Path], out_dir: Path, gif: bool
) -> dict[str, Path]:
    """:func:`variant_figures` of the variant ``key`` from its saved runs (``configuration
    name → run directory``): what one worker of :func:`reproduction_figures` does."""
    logs = {Configuration.parse(config): load_run(directory)
            for config, directory in run_dirs.items()}
    return variant_figures(variant(key), logs, out_dir, gif=gif)


def reproduction_figures(
    run_dirs: Mapping[tuple[str, str], Path], out_dir: Path, *, gif: bool = True,
    jobs: int = 1,
) -> dict[str, Path]:
    """Figures of the reproduction, per variant, like the paper's Fig. 3 and Fig. 4.

    Parameters
    ----------
    run_dirs
        ``(variant key, configuration name) → run directory`` of every saved run.
    out_dir
        Where the figures go (created if needed).
    gif
        Whether to write the animations of the variants that have them.
    jobs
        Worker processes (≥ 1): the variants' figures are independent, and drawing them took
        as long as the runs (docs/performance.md). The files are the same either way.

    Raises
    ------
    ValueError
        If ``jobs`` < 1.
    """
    if jobs < 1:
        raise ValueError(f"jobs must be >= 1, got {jobs}")
    out_dir.mkdir(parents=True, exist_ok=True)
    groups: dict[str, dict[str, Path]] = {}
    for (key, config), directory in run_dirs.items():
        groups.setdefault(key, {})[config] = directory
    workers = min(jobs, len(groups))
    if workers <= 1:
        per_variant = [_variant_figures_from_runs(key, dirs, out_dir, gif)
                       for key, dirs in groups.items()]
    else:
        with ProcessPoolExecutor(max_workers=workers, initializer=_leave_interrupts) as pool:
            per_variant = list(pool.map(_variant_figures_from_runs, groups,
                                        groups.values(), repeat(out_dir), repeat(gif)))
    figures: dict[str, Path] = {}
    for found in per_variant:
        figures.update(found)
    return figures
