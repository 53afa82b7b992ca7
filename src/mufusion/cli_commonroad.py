"""``mufusion import-commonroad``: a CommonRoad scenario file's route as a ``road`` scenario.

The options are checked before the file is read (exit 2 naming the option); the file, the route
and its geometry are checked next, each failure again exit 2 naming the problem. The CommonRoad
packages (the ``commonroad`` extra) are imported by :mod:`mufusion.road.commonroad`'s functions
only when a file is read.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated, Any

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
    from mufusion.road.commonroad import SMOOTHINGS, RunLimits
    from mufusion.scenarios.base import Scenario
    from mufusion.scenarios.road_kind import START_ROOM_M
    from mufusion.scenarios.sections import Friction, PlannerSettings
    from mufusion.vehicle.params import PRESETS

    try:
        if vehicle not in PRESETS:
            raise ValueError(f"--vehicle must be one of {sorted(PRESETS)}, got {vehicle!r}")
        if speed_mps is not None:
            _check_like("--speed-mps", speed_mps, _field_type(Scenario, "initial_speed_mps"))
        if mu is not None:
            _check_like("--mu", mu, Friction)
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
        limits = RunLimits(start_room_m=START_ROOM_M,
                           preview_s=planner.horizon_steps * planner.dt_s,
                           vehicle_length_m=params.length_m, min_run_s=MIN_RUN_S,
                           max_duration_s=_field_max(Scenario, "duration_s"))
        speed_guess = speed_mps or (DEFAULT_SPEED_MPS if chain is not None else None)
        if length_m is not None and speed_guess is not None \
                and length_m < limits.min_route_length_m(speed_guess):
            raise ValueError(f"--length-m {length_m:g} is shorter than a run needs: at least "
                             f"{limits.min_route_length_m(speed_guess):.0f} m at "
                             f"{speed_guess:g} m/s")
        road, run, text = _import(file, out, planning_problem, chain, length_m, smoothing,
                                  vehicle, speed_mps, mu, limits)
    except ValueError as err:
        raise _fail(str(err)) from None
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(text)
    except OSError as err:
        raise _fail(f"--out {str(out)!r} is not writable: {err}") from None
    _report(road, run, out)


def _field_type(model: Any, name: str) -> Any:
    """A model field's type with its constraints, for checking an option against it."""
    info = model.model_fields[name]
    return Annotated.__class_getitem__((info.annotation, *info.metadata))  # type: ignore[attr-defined]


def _field_max(model: Any, name: str) -> float:
    """A model field's upper bound (``le``)."""
    return next(float(m.le) for m in model.model_fields[name].metadata
                if getattr(m, "le", None) is not None)


def _check_like(option: str, value: float, kind: Any) -> None:
    """Raise ``ValueError`` naming ``option`` unless ``value`` validates as ``kind``."""
    from pydantic import TypeAdapter, ValidationError

    try:
        TypeAdapter(kind).validate_python(value)
    except ValidationError as err:
        raise ValueError(f"{option} {value:g}: {err.errors()[0]['msg']}") from None


def _import(file: Path, out: Path, planning_problem: int | None, chain: list[int] | None,
            length_m: float | None, smoothing: str, vehicle: str, speed_mps: float | None,
            mu: float | None, limits: Any) -> tuple[Any, Any, str]:
    """Read, import, choose the run, write the TOML text and validate it as a ``road``
    scenario (the kind's own checks: lane against vehicle, curves against its turning circle,
    the path's length, obstacles on the road), all before anything is written."""
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        import tomli as tomllib

    from mufusion.estimators.classes import PAPER_CLASSES
    from mufusion.road.commonroad import (
        UNDERGROUND_SURFACE,
        choose_run,
        clear_of_start,
        import_road,
        read_commonroad,
        road_scenario_toml,
    )
    from mufusion.scenarios.loading import scenario_from_dict
    from mufusion.vehicle.params import PRESETS

    params = PRESETS[vehicle]
    road = import_road(read_commonroad(file), problem_id=planning_problem, lanelet_ids=chain,
                       length_m=length_m, smoothing=smoothing)
    speed = speed_mps or road.start_speed_mps or DEFAULT_SPEED_MPS
    run = choose_run(road, speed_mps=speed, limits=limits)
    road = clear_of_start(road, run, vehicle_length_m=params.length_m,
                          vehicle_width_m=params.width_m)
    surfaces = {c.name: c for c in PAPER_CLASSES}
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
    scenario_from_dict(tomllib.loads(text), source=f"imported from {file.name} "
                       f"({road.route_label})")
    return road, run, text


def _report(road: Any, run: Any, out: Path) -> None:
    """Print what the import measured and what it dropped."""
    lanes = road.lanes
    nearer = np.minimum(lanes.left_m, lanes.right_m)
    console.print(
        f"{road.route_label}: {road.length_m:.0f} m, tightest bend R "
        f"{road.smallest_radius_m:.1f} m (consecutive points {road.smallest_vertex_radius_m:.1f}"
        f" m); nearer lane boundary {nearer.min():.2f}–{nearer.max():.2f} m from the path → "
        f"own lane {lanes.ego_width_m:.2f} m; opposing lane {lanes.opposing_width_m:.2f} m "
        f"({100 * lanes.opposing_coverage:.0f} % of the path); {len(road.obstacles)} obstacles"
    )
    for message in road.dropped:
        console.print(f"dropped {message}")
    console.print(f"start s = {run.start_s_m:g} m at {run.initial_speed_mps:g} m/s for "
                  f"{run.duration_s:g} s; wrote [bold]{out}[/bold]")
