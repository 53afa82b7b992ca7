"""``mufusion import-commonroad``: a CommonRoad scenario file's route as a ``road`` scenario.

The options are checked before the file is read (exit 2 naming the option); the file, the route
and its geometry are checked next, each failure again exit 2 naming the problem. The CommonRoad
packages (the ``commonroad`` extra) are imported by :mod:`mufusion.road.commonroad`'s functions
only when a file is read.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape

console = Console(stderr=True)

# A run shorter than this shows nothing of the road [s].
MIN_RUN_S = 2.0
# Initial speed of a lanelet route (no planning problem to take it from) [m/s].
DEFAULT_SPEED_MPS = 10.0


def _fail(message: str) -> typer.Exit:
    console.print(f"[red]error:[/red] {escape(message)}")
    return typer.Exit(code=2)


def _lanelet_chain(text: str) -> list[int]:
    try:
        chain = [int(part) for part in text.split(",")]
    except ValueError:
        raise ValueError(f"--lanelet must be a lanelet ID or IDs separated by commas, got "
                         f"{text!r}") from None
    return chain


def import_commonroad(
    file: Annotated[Path, typer.Argument(help="CommonRoad scenario XML (2018b or 2020a).")],
    out: Annotated[Path, typer.Option("--out", "-o", help="The road scenario TOML to write.")],
    planning_problem: Annotated[
        int | None, typer.Option(help="Route of this planning problem (route planner's "
                                 "shortest path to its goal).")] = None,
    lanelet: Annotated[
        str | None, typer.Option(help="Route from this lanelet along its successors; where they "
                                 "branch, name the branch: ID,ID,...")] = None,
    length_m: Annotated[
        float | None, typer.Option(help="Route length in m (with --lanelet; cuts a planning "
                                   "problem's route).")] = None,
    vehicle: Annotated[str, typer.Option(help="truck or car.")] = "truck",
    speed_mps: Annotated[
        float | None, typer.Option(help="Initial speed in m/s (default: the planning problem's, "
                                   "else 10).")] = None,
    smoothing: Annotated[
        str, typer.Option(help="commonroad-clcs smoothing of the route: curve_subdivision or "
                          "elastic_band.")] = "curve_subdivision",
    mu: Annotated[
        float | None, typer.Option(help="Friction coefficient everywhere (default: from the "
                                   "file's underground label, else dry).")] = None,
) -> None:
    """Import a CommonRoad scenario's route, lanes and obstacles as a `road` scenario TOML."""
    from mufusion.estimators.classes import PAPER_CLASSES
    from mufusion.road.commonroad import SMOOTHINGS
    from mufusion.scenarios.sections import PlannerSettings
    from mufusion.vehicle.params import PRESETS

    surfaces = {c.name: c for c in PAPER_CLASSES}
    try:
        if vehicle not in PRESETS:
            raise ValueError(f"--vehicle must be one of {sorted(PRESETS)}, got {vehicle!r}")
        if speed_mps is not None and not 0.0 < speed_mps <= 40.0:
            raise ValueError(f"--speed-mps must be in (0, 40] m/s, got {speed_mps}")
        if mu is not None and not 0.1 <= mu <= 1.5:
            raise ValueError(f"--mu must be in [0.1, 1.5], got {mu}")
        if smoothing not in SMOOTHINGS:
            raise ValueError(f"--smoothing must be one of {sorted(SMOOTHINGS)}, got "
                             f"{smoothing!r}")
        if (planning_problem is None) == (lanelet is None):
            raise ValueError("give either --planning-problem ID or --lanelet ID --length-m L")
        if lanelet is not None and length_m is None:
            raise ValueError("--lanelet needs --length-m (the route's length in metres)")
        if length_m is not None and not 0.0 < length_m <= 10_000.0:
            raise ValueError(f"--length-m must be in (0, 10000] m, got {length_m}")
        chain = None if lanelet is None else _lanelet_chain(lanelet)
        if out.exists() and out.is_dir():
            raise ValueError(f"--out {str(out)!r} is a directory, not a file")
        params = PRESETS[vehicle]
        planner = PlannerSettings()
        preview_s = planner.horizon_steps * planner.dt_s
        from mufusion.road.commonroad import (
            UNDERGROUND_SURFACE,
            choose_run,
            clear_of_start,
            import_road,
            read_commonroad,
            road_scenario_toml,
        )
        speed_guess = speed_mps or (DEFAULT_SPEED_MPS if chain is not None else None)
        if length_m is not None and speed_guess is not None:
            from mufusion.road.commonroad import min_route_length_m

            need = min_route_length_m(speed_guess, preview_s, params.length_m, MIN_RUN_S)
            if length_m < need:
                raise ValueError(f"--length-m {length_m:g} is shorter than a run needs: at least "
                                 f"{need:.0f} m at {speed_guess:g} m/s")
        source = read_commonroad(file)
        road = import_road(source, problem_id=planning_problem, lanelet_ids=chain,
                           length_m=length_m, smoothing=smoothing)
        max_kappa = math.tan(params.max_steer_rad) / params.wheelbase_m
        if road.smallest_radius_m < 1.0 / max_kappa:
            raise ValueError(f"{road.route_label}: the path's smallest radius "
                             f"{road.smallest_radius_m:.1f} m is sharper than the {vehicle} can "
                             f"steer ({1.0 / max_kappa:.1f} m)")
        if road.lanes.ego_width_m <= params.width_m:
            raise ValueError(f"{road.route_label}: the own lane ({road.lanes.ego_width_m:.2f} m "
                             f"measured) is not wider than the {vehicle} ({params.width_m} m)")
        speed = speed_mps or road.start_speed_mps or DEFAULT_SPEED_MPS
        run = choose_run(road, speed_mps=min(40.0, speed), preview_s=preview_s,
                         vehicle_length_m=params.length_m, min_run_s=MIN_RUN_S,
                         max_duration_s=120.0)
        road = clear_of_start(road, run, vehicle_length_m=params.length_m,
                              vehicle_width_m=params.width_m)
    except ValueError as err:
        raise _fail(str(err)) from None
    if mu is not None:
        mu_value, mu_source = mu, f"--mu {mu:g}"
    elif road.underground in UNDERGROUND_SURFACE:
        surface = surfaces[UNDERGROUND_SURFACE[road.underground]]
        mu_value = surface.value
        mu_source = (f"the file's underground '{road.underground}' → the camera's "
                     f"{surface.name} class value {surface.value:g} (paper Table I)")
    else:
        mu_value = surfaces["dry"].value
        mu_source = (f"no underground label in the file ({road.underground or 'none'}) → the "
                     f"dry class value {mu_value:g} (paper Table I)")
    text = road_scenario_toml(road, run, vehicle=vehicle, mu=mu_value, mu_source=mu_source)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(text)
    except OSError as err:
        raise _fail(f"--out {str(out)!r} is not writable: {err}") from None
    lanes = road.lanes
    nearer = np.minimum(lanes.left_m, lanes.right_m)
    console.print(
        f"{road.route_label}: {road.length_m:.0f} m, tightest bend R "
        f"{road.smallest_radius_m:.1f} m (consecutive points {road.smallest_vertex_radius_m:.1f}"
        f" m); nearer lane boundary {nearer.min():.2f}–"
        f"{nearer.max():.2f} m from the path → own lane "
        f"{lanes.ego_width_m:.2f} m; opposing lane {lanes.opposing_width_m:.2f} m "
        f"({100 * lanes.opposing_coverage:.0f} % of the path); μ {mu_value:g}; "
        f"{len(road.obstacles)} obstacles"
    )
    for message in road.dropped:
        console.print(f"dropped {message}")
    console.print(f"start s = {run.start_s_m:g} m at {run.initial_speed_mps:g} m/s for "
                  f"{run.duration_s:g} s; wrote [bold]{out}[/bold]")
