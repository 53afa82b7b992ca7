"""Figure sets for one run (``mufusion run``) and for the reproduction (``mufusion reproduce``).

Which runs go side by side and at which positions follows the paper's Fig. 3 (turn: L vs F at
s = 0, 15, 30, 55 m) and Fig. 4 (pop-up: P vs F at s = 0, 2, 18, 40 m).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from mufusion.plots.animation import animate_run
from mufusion.plots.estimate import plot_fused_estimate
from mufusion.plots.forces import plot_planned_forces
from mufusion.plots.snapshots import plot_snapshots
from mufusion.plots.traces import plot_lateral_and_speed
from mufusion.sim.log import RunLog, load_run

SNAPSHOT_POSITIONS_M: dict[str, tuple[float, ...]] = {
    "turn": (0.0, 15.0, 30.0, 55.0),
    "popup": (0.0, 2.0, 18.0, 40.0),
}
# The configuration that fails in each scenario, shown above the fused one (paper Fig. 3, 4).
CONTRAST_CONFIG: dict[str, str] = {"turn": "L", "popup": "P"}


def _reachable_positions(log: RunLog, positions: Sequence[float]) -> list[float]:
    ts = log.timeseries
    travelled = float(ts["s_m"].iloc[-1] - log.meta.get("start_s_m", ts["s_m"].iloc[0]))
    return [p for p in positions if p <= travelled]


def single_run_figures(log: RunLog, out_dir: Path, *, gif: bool = True) -> dict[str, Path]:
    """Figures of one run: snapshots, lateral offset and speed, planned forces, the estimate."""
    out_dir.mkdir(parents=True, exist_ok=True)
    scenario = log.meta["scenario"]["name"]
    t_c = float(log.meta.get("comparison_time_s", 0.0))
    figures: dict[str, Path] = {}
    positions = _reachable_positions(log, SNAPSHOT_POSITIONS_M.get(scenario, (0.0,)))
    if positions:
        figures["snapshots"] = plot_snapshots([log], positions, out_dir / "snapshots.png")
    figures["traces"] = plot_lateral_and_speed([log], out_dir / "lateral_speed.png")
    figures["forces"] = plot_planned_forces([log], t_c, out_dir / "planned_forces.png")
    if not log.estimates.empty and log.estimates["mean"].notna().any():
        figures["estimate"] = plot_fused_estimate(log, t_c, out_dir / "fused_estimate.png")
    if gif:
        figures["animation"] = animate_run(log, out_dir / "run.gif")
    return figures


def reproduction_figures(
    results: Sequence[tuple[Any, Any, Path]], out_dir: Path, *, gif: bool = True
) -> dict[str, Path]:
    """Figures of the reproduction, per scenario variant, like the paper's Fig. 3 and Fig. 4.

    ``results`` are ``(spec, metrics, run_directory)`` triples from
    :func:`mufusion.scenarios.campaign.run_campaign`.
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    groups: dict[tuple[str, str], dict[str, Path]] = {}
    for spec, _metrics, directory in results:
        groups.setdefault((spec.scenario, spec.variant), {})[spec.config] = directory
    figures: dict[str, Path] = {}
    for (scenario, variant), dirs in groups.items():
        logs = {config: load_run(d) for config, d in dirs.items()}
        tag = f"{scenario}-{''.join(c if c.isalnum() else '-' for c in variant)}".lower()
        t_c = float(next(iter(logs.values())).meta.get("comparison_time_s", 0.0))
        ordered = [logs[c] for c in ("GT", "L", "P", "F", "F-safe") if c in logs]
        pair = [logs[c] for c in (CONTRAST_CONFIG.get(scenario, "P"), "F") if c in logs]
        if pair:
            positions = _reachable_positions(pair[-1], SNAPSHOT_POSITIONS_M.get(scenario, (0.0,)))
            if positions:
                figures[f"{tag}/snapshots"] = plot_snapshots(
                    pair, positions, out_dir / f"{tag}-snapshots.png"
                )
        figures[f"{tag}/traces"] = plot_lateral_and_speed(
            ordered, out_dir / f"{tag}-lateral_speed.png"
        )
        figures[f"{tag}/forces"] = plot_planned_forces(
            ordered, t_c, out_dir / f"{tag}-planned_forces.png"
        )
        if "F" in logs:
            figures[f"{tag}/estimate"] = plot_fused_estimate(
                logs["F"], t_c, out_dir / f"{tag}-fused_estimate.png"
            )
        if gif and variant in ("paper", "paper mu=1.0"):
            for config in (CONTRAST_CONFIG.get(scenario, "P"), "F"):
                if config in logs:
                    figures[f"{tag}/{config}/animation"] = animate_run(
                        logs[config], out_dir / f"{tag}-{config}.gif"
                    )
    return figures
