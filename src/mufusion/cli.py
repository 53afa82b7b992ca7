"""The ``mufusion`` command line.

Subcommands are registered here; each one is a thin layer over the library (validation of the
arguments, a progress bar, files written), never physics or estimation of its own.
"""

from __future__ import annotations

import json
import logging
import os
import signal
import time
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from mufusion.cli_campaign_diff import campaign_diff
from mufusion.cli_commonroad import import_commonroad
from mufusion.cli_progress import console, print_table, progress_bar, run_specs
from mufusion.cli_progress import fail as _fail
from mufusion.cli_shared import calibrate_shared, fleet

app = typer.Typer(
    name="mufusion",
    help=(
        "Friction-estimate fusion for traction-adaptive motion planning: reproduce the paper's "
        "experiments, run scenarios in closed loop and inspect the GP fusion."
    ),
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
app.command("import-commonroad")(import_commonroad)
app.command()(fleet)  # `mufusion fleet` (cli_shared.py)
app.command("campaign-diff")(campaign_diff)


@app.callback()
def _main(
    verbose: Annotated[bool, typer.Option("--verbose", "-v", help="Log solver warnings.")] = False,
) -> None:
    """mufusion: fuse camera and slip-based friction estimates and drive on them in closed loop."""
    logging.basicConfig(
        level=logging.INFO if verbose else logging.ERROR,
        format="%(levelname)s %(name)s: %(message)s",
    )


@app.command()
def run(
    scenario: Annotated[
        str, typer.Argument(help="Built-in scenario ('turn' or 'popup') or a scenario .toml file.")
    ],
    configs: Annotated[
        list[str] | None,
        typer.Option(
            "--config",
            "-c",
            help="Friction estimate the planner uses (one; default F): GT (ground truth), "
            "L (local only), P (predictive only), F (fused, paper), F-safe (fused, worst-case "
            "safe), F+shared / F-safe+shared (also the [shared] reports file's reports), or your "
            "own as module:Class (imported from the current directory) or an entry point of "
            "mufusion.friction_sources.",
        ),
    ] = None,
    set_: Annotated[
        list[str] | None,
        typer.Option("--set", help="Override a scenario field, e.g. --set friction.mu=0.89."),
    ] = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="Output directory.")] = Path(
        "results/run"
    ),
    gif: Annotated[bool, typer.Option(help="Also write an animated GIF of the run.")] = True,
    planner: Annotated[
        str | None,
        typer.Option(help="Your own planner: module:Class (called with the vehicle's parameters "
                     "and the planner configuration) or an entry point of mufusion.planners."),
    ] = None,
    controller: Annotated[
        str | None,
        typer.Option(help="Your own controller: module:Class or an entry point of "
                     "mufusion.controllers (called like a planner plug-in)."),
    ] = None,
) -> None:
    """Run one scenario in closed loop: writes the run log, summary.json and figures.

    The exit code is 0 when the run completes, also when the vehicle crashes: that is a result.
    """
    if configs is not None and len(configs) > 1:
        # Typer keeps the last of a repeated option: refuse rather than drop the others.
        _fail(f"--config: run drives one configuration, got {len(configs)} "
              f"({', '.join(configs)}); a campaign file's configs = [...] runs several")
    config = "F" if not configs else configs[0]
    from mufusion import cli_input  # the light checks; the heavy stack after them
    try:
        cfg = cli_input.run_input(scenario, config, list(set_ or []), out, planner, controller)
    except ValueError as err:
        _fail(str(err))
    from mufusion.metrics import compute_metrics
    from mufusion.plots.run_figures import single_run_figures
    from mufusion.scenarios.runner import run_scenario

    with progress_bar(console) as progress:
        task = progress.add_task(f"{cfg.name} / {config}", total=cfg.duration_s)
        log = run_scenario(cfg, config, progress=lambda t: progress.update(task, completed=t),
                           planner=planner, controller=controller)
        progress.update(task, completed=cfg.duration_s)
    log.save(out / "log")
    metrics = compute_metrics(log)
    summary = {"scenario": cfg.name, "config": config, **metrics.to_dict()}
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    figures = single_run_figures(log, out / "figures", gif=gif)
    print_table([summary])
    console.print(f"log, summary.json and {len(figures)} figures in [bold]{out}[/bold]")


@app.command()
def reproduce(
    out: Annotated[Path, typer.Option("--out", "-o", help="Output directory.")] = Path("results"),
    jobs: Annotated[
        int | None, typer.Option(help="Worker processes (default: one per CPU core).")
    ] = None,
    car: Annotated[
        bool, typer.Option(help="Also run both scenarios with the passenger car.")
    ] = True,
    gif: Annotated[bool, typer.Option(help="Write animated GIFs of the key runs.")] = True,
    ablation: Annotated[
        bool,
        typer.Option(help="Also apply each of the authors' settings alone to the paper-text "
                     "variants (48 more runs) and report what each does."),
    ] = False,
) -> None:
    """Reproduce the paper: every configuration in both scenarios, figures and a report."""
    from mufusion import cli_input  # the light checks; the heavy stack after them
    try:
        cli_input.check_jobs(jobs)
        cli_input.check_out_dir(out)
    except ValueError as err:
        _fail(str(err))
    from mufusion.plots.run_figures import reproduction_figures
    from mufusion.reproduction import explain_differences, reproduction_specs, write_report
    from mufusion.reproduction.ablation import ablation_specs

    specs = reproduction_specs(include_car=car)
    extra = ablation_specs() if ablation else []
    started = time.perf_counter()
    from mufusion.campaign import with_indices

    # One index per run over both lists: run directory names never collide.
    results, all_runs = run_specs(with_indices([*specs, *extra]), out, jobs, console)
    runs, ablation_runs = all_runs[: len(specs)], all_runs[len(specs):]
    run_dirs = {(spec.variant, spec.config): directory
                for spec, _m, directory in results[: len(specs)]}
    # The figures in as many processes as the runs had (one per core by default).
    figures = reproduction_figures(run_dirs, out / "figures", gif=gif,
                                   jobs=jobs or os.cpu_count() or 1)
    elapsed = time.perf_counter() - started
    summary = {"runs": runs, "elapsed_s": round(elapsed, 1)}
    if ablation_runs:
        summary["ablation"] = ablation_runs
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    md, html = write_report(summary, out, figures, explain_differences(runs))
    print_table(runs)
    console.print(f"{len(runs)} runs in {elapsed:.0f} s; report: [bold]{md}[/bold], {html.name}")


@app.command()
def campaign(
    file: Annotated[Path, typer.Argument(help="Campaign TOML: scenarios, configs, grid, seeds.")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Output directory.")] = Path(
        "results/campaign"
    ),
    jobs: Annotated[
        int | None,
        typer.Option(help="Parallel runs (default: one per CPU core; local Ray: its CPUs)."),
    ] = None,
    shard: Annotated[
        str,
        typer.Option(
            help="K/N: run only the K-th of N shards (0-based), e.g. one cluster array job each; "
            "a variant and its GT run always share a shard."
        ),
    ] = "0/1",
    engine: Annotated[
        str, typer.Option(help="Where runs execute: pool (processes on this machine) or ray.")
    ] = "pool",
    address: Annotated[
        str | None,
        typer.Option(help="Ray cluster address (with --engine ray); default: a local instance."),
    ] = None,
    resume: Annotated[
        bool, typer.Option("--resume", help="Continue the campaign in --out: skip complete runs.")
    ] = False,
    overwrite: Annotated[
        bool, typer.Option("--overwrite", help="Clear --out (an earlier campaign) first.")
    ] = False,
) -> None:
    """Run a campaign of scenario variants × configurations × seeds.

    Writes every run's log under OUT/runs, summary.json (a `runs` list: parameters, metrics,
    utilisation against the variant's GT run, or the run's error) and the same rows as one table,
    results.parquet / results.csv. Exit code 0: every run completed; 1: some runs failed (they
    are rows with their error); 2: invalid input; 130 / 143: interrupted by Ctrl-C (SIGINT) /
    SIGTERM (summary marked partial, the resume command printed).
    """
    from mufusion import cli_input  # the light checks; the heavy stack after them
    try:
        checked = cli_input.campaign_input(file, out, jobs=jobs, shard=shard, engine=engine,
                                           address=address, resume=resume, overwrite=overwrite)
    except ValueError as err:
        _fail(str(err))
    from mufusion.campaign import CampaignInterrupted, execute_campaign, write_results
    from mufusion.campaign.results import result_rows

    plan, specs, k, n = checked.plan, checked.specs, checked.shard, checked.shards
    started = time.perf_counter()
    pending: list = []
    stopped_by: signal.Signals | None = None  # the signal that left runs pending
    with progress_bar(console) as progress:
        task = progress.add_task("runs", total=len(specs))
        try:
            results = execute_campaign(
                specs, out / "runs", engine=checked.engine, jobs=jobs, address=address,
                resume=resume, on_done=lambda _s: progress.advance(task),
            )
        except CampaignInterrupted as stop:
            results, pending = stop.finished, stop.pending
            stopped_by = stop.signal if pending else None
        except ValueError as err:
            _fail(str(err))
    elapsed = time.perf_counter() - started
    info = {"campaign": str(file), "name": plan.name, "shard": f"{k}/{n}", "engine": engine,
            "elapsed_s": round(elapsed, 1),
            **({} if stopped_by is None else {"interrupted_by": stopped_by.name})}
    summary = write_results(out, results, info, partial=bool(pending), pending=len(pending))
    rows = result_rows(results, out)
    if len(rows) <= MAX_TABLE_ROWS:
        print_table(rows)
    failed = [r for r in rows if r["error"] is not None]
    for row in failed:
        console.print(f"[red]failed:[/red] {row['run']}: {row['error']}")
    resumed = sum(r.resumed for r in results)
    console.print(
        f"{len(rows) - len(failed)} runs completed ({resumed} found complete), {len(failed)} "
        f"failed in {elapsed:.0f} s; summary: {summary}, table: {out / 'results.parquet'}"
    )
    if stopped_by is not None:
        again = cli_input.resume_command(file, out, shard=shard, engine=engine, address=address,
                                         jobs=jobs)
        console.print(
            f"[yellow]interrupted ({stopped_by.name}):[/yellow] {len(pending)} runs did not run; "
            f"summary.json is marked partial. Resume with:\n  {again}"
        )
        raise typer.Exit(code=128 + stopped_by.value)
    if failed:
        raise typer.Exit(code=1)


# Campaigns larger than this print counts only; the table is in summary.json / results.csv.
MAX_TABLE_ROWS = 40


@app.command("campaign-report")
def campaign_report(
    directory: Annotated[Path, typer.Argument(help="Output directory of `mufusion campaign`.")],
    out: Annotated[
        Path | None, typer.Option("--out", "-o", help="Report directory (default: DIR/report).")
    ] = None,
) -> None:
    """Monte Carlo report of a campaign: outcome rates per configuration with Wilson 95 %
    intervals, distributions of the graded outcomes, heat maps over the grid, as report.md and
    report.html."""
    from mufusion.campaign.report import load_campaign_results, write_campaign_report
    from mufusion.plots.campaign import campaign_figures

    try:
        data = load_campaign_results(directory)
    except ValueError as err:
        _fail(str(err))
    target = out if out is not None else directory / "report"
    try:
        target.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        _fail(f"--out {str(target)!r} is not writable: {err}")
    figures = campaign_figures(data, target / "figures")
    md, html = write_campaign_report(data, figures, target)
    console.print(f"report: [bold]{md}[/bold], {html.name} ({len(figures)} figures)")


@app.command("fusion-demo")
def fusion_demo(
    out: Annotated[Path, typer.Option("--out", "-o", help="Output PNG file.")] = Path(
        "results/fusion_demo.png"
    ),
    mode: Annotated[
        str, typer.Option(help="Fusion mode to draw: paper, safe or both (side by side).")
    ] = "both",
    mu_before: Annotated[float, typer.Option(help="True μ near the vehicle [-].")] = 0.8,
    mu_after: Annotated[float, typer.Option(help="True μ after the change [-].")] = 0.3,
    change_ahead_m: Annotated[
        float, typer.Option(help="Distance ahead where μ changes [m].")
    ] = 25.0,
    local_error: Annotated[
        str, typer.Option(help="Local estimator error: none, worst_over, worst_under, random.")
    ] = "none",
    predictive_error: Annotated[
        str, typer.Option(help="Camera error: none, worst_over, worst_under, random.")
    ] = "none",
    seed: Annotated[int, typer.Option(help="Seed for the 'random' error models.")] = 0,
) -> None:
    """Draw the GP fusion for a vehicle approaching a change of friction (cf. the paper's Fig. 2):
    prior band, local and camera data with error bars, posterior band and the fused estimate."""
    from mufusion.plots.fusion_demo import fusion_demo_figure

    try:
        path = fusion_demo_figure(
            out,
            mode=mode,
            mu_before=mu_before,
            mu_after=mu_after,
            change_ahead_m=change_ahead_m,
            local_error=local_error,
            predictive_error=predictive_error,
            seed=seed,
        )
    except ValueError as exc:
        _fail(str(exc))
    console.print(f"wrote {path}")


@app.command()
def calibrate(
    horizons: Annotated[
        int, typer.Option(help="Random horizons to draw (the acceptance run uses 100000).")
    ] = 100_000,
    seed: Annotated[int, typer.Option(help="Seed of the random generator (>= 0).")] = 0,
    out: Annotated[Path, typer.Option("--out", "-o", help="Output directory.")] = Path(
        "results/calibration"
    ),
    shared: Annotated[bool, typer.Option(help="With shared reports: by age, wrong share.")] = False,
) -> None:
    """Calibrate the fusion without a closed loop: random horizons (class layouts, errors within
    the declared margins, local estimate present or absent) fused in both modes; writes
    calibration.json and calibration.png and prints the over-estimate rate per distance."""
    import numpy as np

    from mufusion.fusion.calibration import calibrate_fusion
    from mufusion.plots.calibration import calibration_figure

    if horizons < 1:
        _fail(f"--horizons must be >= 1, got {horizons}")
    if seed < 0:
        _fail(f"--seed must be >= 0, got {seed}")
    if out.exists() and not out.is_dir():
        _fail(f"--out must be a directory, got the file {out}")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        _fail(f"--out cannot be created: {err}")
    if shared:
        return calibrate_shared(horizons, seed, out)
    started = time.perf_counter()
    result = calibrate_fusion(np.random.default_rng(seed), n_horizons=horizons)
    elapsed = time.perf_counter() - started
    payload = {"command": {"horizons": horizons, "seed": seed}, **result.to_dict()}
    (out / "calibration.json").write_text(json.dumps(payload, indent=2))
    figure = calibration_figure(result, out / "calibration.png")
    table = Table(title=f"fusion calibration, {horizons} horizons, seed {seed}")
    for header in ("s ahead m", "over % paper", "over % safe", "cover % paper", "cover % safe"):
        table.add_column(header, justify="right")
    shown = [i for i, s in enumerate(result.s_ahead_m) if s in (0, 5, 10, 20, 30, 40, 50)]
    rows = [(f"{result.s_ahead_m[i]:g}", i) for i in shown] + [("all", None)]
    for label, i in rows:
        cells = []
        for field in ("over_estimate_rate", "lower_coverage"):
            for cal in (result.paper, result.safe):
                value = getattr(cal, field) if i is None else getattr(cal, f"{field}_by_s")[i]
                cells.append(f"{100 * value:.2f}")
        table.add_row(label, *cells)
    Console().print(table)
    console.print(
        f"nominal lower-bound coverage {100 * result.nominal_coverage:.1f} %; "
        f"{elapsed:.1f} s; {out / 'calibration.json'}, {figure.name}"
    )


if __name__ == "__main__":  # pragma: no cover
    app()
