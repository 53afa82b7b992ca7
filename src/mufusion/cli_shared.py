"""The command line of shared reports (issue 40): ``mufusion fleet`` (N vehicles on one road,
each one's estimates shared with those behind it; :mod:`mufusion.scenarios.fleet`) and
``mufusion calibrate --shared`` (:mod:`mufusion.fusion.calibration_shared`). Registered on the
``mufusion`` app by :mod:`mufusion.cli` (this module does not import it: no cycle)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer

from mufusion.cli_progress import console, print_table
from mufusion.cli_progress import fail as _fail


def fleet(
    scenario: Annotated[
        str, typer.Argument(help="Built-in scenario ('turn' or 'popup') or a scenario .toml file.")
    ],
    vehicles: Annotated[int, typer.Option(help="Vehicles driving the road one after another.")] = 3,
    config: Annotated[
        str, typer.Option("--config", "-c", help="Every vehicle's configuration: F+shared or "
                          "F-safe+shared to use the reports (any built-in one as a baseline).")
    ] = "F-safe+shared",
    set_: Annotated[
        list[str] | None,
        typer.Option("--set", help="Override a scenario field, e.g. --set shared.tau_s=600."),
    ] = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="Output directory.")] = Path(
        "results/fleet"
    ),
) -> None:
    """Run a fleet: vehicle k gets the local estimates of vehicles 1 … k−1 as shared reports
    (after the [shared] section's delay, link and wrong reports); writes each vehicle's log and
    summary, the fused band of the last vehicle with its reports, and vehicle 1 against N."""
    from mufusion import cli_input
    from mufusion.configurations import CONFIGURATION_NAMES

    if config not in CONFIGURATION_NAMES:
        _fail(f"--config must be one of {list(CONFIGURATION_NAMES)}, got {config!r}")
    if not 1 <= vehicles <= 50:
        _fail(f"--vehicles must lie in [1, 50], got {vehicles}")
    try:
        cfg = cli_input.run_input(scenario, config, list(set_ or []), out)
    except ValueError as err:
        _fail(str(err))
    from mufusion.metrics import compute_metrics
    from mufusion.plots.fleet import plot_band, plot_first_last
    from mufusion.scenarios.fleet import run_fleet

    rows, last_reports = [], []

    def done(k, log, inbox):
        nonlocal last_reports
        log.save(out / f"vehicle-{k}" / "log")
        received = [] if inbox is None else inbox.at(cfg.comparison_time_s)
        last_reports = received
        rows.append({"scenario": f"{cfg.name} / vehicle {k}", "config": config,
                     "reports_received": len(received), **compute_metrics(log).to_dict()})
        console.print(f"vehicle {k} of {vehicles} done ({len(received)} reports at "
                      f"t = {cfg.comparison_time_s:g} s)")

    logs = run_fleet(cfg, config, vehicles, on_vehicle=done)
    (out / "summary.json").write_text(json.dumps(rows, indent=2))
    figures = []
    if logs[-1].estimates["mean"].notna().any():
        figures.append(plot_band(logs[-1], cfg.comparison_time_s, out / "band_last.png",
                                 last_reports))
        figures.append(plot_first_last(logs[0], logs[-1], cfg.comparison_time_s,
                                       out / "first_vs_last.png"))
    print_table(rows)
    console.print(f"{vehicles} logs, summary.json and {len(figures)} figures in [bold]{out}[/bold]")


def calibrate_shared(horizons: int, seed: int, out: Path) -> None:
    """``mufusion calibrate --shared``: the calibration with reports by age and wrong share
    (at most ``MAX_SHARED_HORIZONS`` horizons: each is fused one by one, per cell and mode)."""
    import numpy as np
    from rich.table import Table

    from mufusion.fusion.calibration_shared import calibrate_shared as run
    from mufusion.fusion.calibration_shared import cells_to_dicts

    n = min(horizons, MAX_SHARED_HORIZONS)
    console.print(f"calibration with shared reports on {n} horizons (seed {seed})")
    cells = run(np.random.default_rng(seed), n)
    payload = {"command": {"horizons": n, "seed": seed, "shared": True},
               "cells": cells_to_dicts(cells)}
    (out / "calibration_shared.json").write_text(json.dumps(payload, indent=2))
    table = Table(title=f"fusion calibration with shared reports, {n} horizons, seed {seed}")
    for header in ("age s", "wrong share", "mode", "over %", "over % no reports",
                   "cover %", "mean μ̂", "mean μ̂ no reports"):
        table.add_column(header, justify="right")
    for c in cells:
        table.add_row(f"{c.age_s:g}", f"{c.wrong_share:g}", c.mode,
                      f"{100 * c.over_estimate_rate:.2f}",
                      f"{100 * c.over_estimate_rate_without:.2f}",
                      f"{100 * c.lower_coverage:.1f}", f"{c.mean_mu_hat:.3f}",
                      f"{c.mean_mu_hat_without:.3f}")
    console.print(table)
    console.print(f"{out / 'calibration_shared.json'}")


MAX_SHARED_HORIZONS = 2000
"""Most horizons ``calibrate --shared`` draws."""
