"""CommonRoad import: a scenario file's route, lanes and obstacles as a ``road`` scenario.

:func:`import_road` reads a CommonRoad XML file (commonroad-io), takes a route (a planning
problem through commonroad-route-planner, or a start lanelet and a length), smooths it with
commonroad-clcs and measures the lanes and the obstacles along it (:mod:`.layout`);
:func:`road_scenario_toml` writes the result in the ``road`` kind's TOML schema
(docs/commonroad.md). The three CommonRoad packages are the optional ``commonroad`` extra and
are imported inside the functions only: the runner never needs them, the written TOML is
self-contained.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from mufusion.road.commonroad.layout import (
    BEND_BASELINE_M,
    ImportedObstacle,
    LaneWidths,
    interval_mid,
    lane_widths,
    obstacles_on_route,
    polyline_curvature_1pm,
    reference_points,
    smallest_radius_m,
    to_frame,
)
from mufusion.road.commonroad.route import (
    DEFAULT_SMOOTHING,
    SMOOTHINGS,
    CommonRoadFile,
    plan_route,
    read_commonroad,
)

__all__ = [
    "DEFAULT_SMOOTHING",
    "SMOOTHINGS",
    "UNDERGROUND_SURFACE",
    "ImportedObstacle",
    "ImportedRoad",
    "LaneWidths",
    "RunChoice",
    "RunLimits",
    "choose_run",
    "clear_of_start",
    "import_road",
    "polyline_curvature_1pm",
    "read_commonroad",
    "road_scenario_toml",
]

UNDERGROUND_SURFACE: dict[str, str] = {
    "wet": "wet",
    "snow": "snow/ice",
    "ice": "snow/ice",
    "clean": "dry",
    "dirty": "dry",
    "damaged": "dry",
}
"""CommonRoad 2020a's ``environment/underground`` labels → the camera's surface classes
(paper Table I, :data:`mufusion.estimators.classes.PAPER_CLASSES`); the class's value is the
imported road's μ. ``unknown`` and an absent label have no class (``--mu`` or the dry default)."""

@dataclass(frozen=True)
class ImportedRoad:
    """A CommonRoad route as the ``road`` kind sees it.

    Attributes
    ----------
    source
        The scenario file.
    route_label, lanelet_ids, smoothing
        What chose the route, its lanelets and the clcs processor that smoothed it.
    origin_m
        The file's coordinates of the path's first point [m]; ``points_m`` are relative to it.
    points_m
        The smoothed path, every :data:`~.layout.POINT_STEP_M` of arc length, ``(n, 2)`` [m].
    s_m
        Progress of each point [m].
    lanes
        The lanes' extent along the path.
    obstacles, dropped
        The obstacles on the road and a message for each one left out.
    underground
        The file's surface label or None.
    start_s_m, start_speed_mps
        The planning problem's initial position's progress [m] and speed [m/s] (None without).
    """

    source: Path
    route_label: str
    lanelet_ids: tuple[int, ...]
    smoothing: str
    origin_m: tuple[float, float]
    points_m: np.ndarray
    s_m: np.ndarray
    lanes: LaneWidths
    obstacles: tuple[ImportedObstacle, ...]
    dropped: tuple[str, ...]
    underground: str | None
    start_s_m: float | None
    start_speed_mps: float | None

    @property
    def length_m(self) -> float:
        """The path's length [m]."""
        return float(self.s_m[-1])

    @property
    def smallest_radius_m(self) -> float:
        """The path's tightest bend [m]: circles through points :data:`~.layout.BEND_BASELINE_M`
        apart (inf on a straight)."""
        return smallest_radius_m(self.points_m, BEND_BASELINE_M, self._step_m)

    @property
    def smallest_vertex_radius_m(self) -> float:
        """The smallest radius through three consecutive points [m], kinks included."""
        return smallest_radius_m(self.points_m, self._step_m, self._step_m)

    @property
    def _step_m(self) -> float:
        return float(self.s_m[1] - self.s_m[0])


def import_road(file: CommonRoadFile, *, problem_id: int | None = None,
                lanelet_ids: list[int] | None = None, length_m: float | None = None,
                smoothing: str = DEFAULT_SMOOTHING) -> ImportedRoad:
    """Import a route of a read CommonRoad file (:func:`read_commonroad`).

    Parameters are those of :func:`.route.plan_route`.

    Raises
    ------
    ValueError
        Naming the option or the geometry that makes the route unusable.
    """
    route = plan_route(file, problem_id=problem_id, lanelet_ids=lanelet_ids, length_m=length_m,
                       smoothing=smoothing)
    points, s = reference_points(route)
    lanes = lane_widths(file.scenario, route, s)
    edges = (-0.5 * lanes.ego_width_m, 0.5 * lanes.ego_width_m + lanes.opposing_width_m)
    obstacles, dropped = obstacles_on_route(file.scenario, route, s, lateral_range_m=edges)
    start_s = start_speed = None
    if route.start_state is not None:
        xy = np.asarray(route.start_state.position.center
                        if hasattr(route.start_state.position, "center")
                        else route.start_state.position, dtype=float)
        sd = to_frame(route.frame, xy)
        start_s = None if sd is None else sd[0]
        start_speed = interval_mid(route.start_state.velocity)
    origin = (float(points[0, 0]), float(points[0, 1]))
    return ImportedRoad(file.path, route.label, route.lanelet_ids, route.smoothing, origin,
                        points - points[0], s, lanes, tuple(obstacles), tuple(dropped),
                        file.underground, start_s, start_speed)


@dataclass(frozen=True)
class RunChoice:
    """Where and how fast the imported run starts and how long it lasts.

    Attributes
    ----------
    start_s_m, initial_speed_mps, duration_s
        The scenario's keys of the same names.
    """

    start_s_m: float
    initial_speed_mps: float
    duration_s: float


@dataclass(frozen=True)
class RunLimits:
    """What a run on an imported road must fit (the caller takes them from the scenario and
    planner settings, which this stage cannot import).

    Attributes
    ----------
    start_room_m
        Least progress of the start [m] (the ``road`` kind's room behind the vehicle).
    preview_s
        The planner's horizon [s]: the plan should stay on the imported path.
    vehicle_length_m
        The body's length [m].
    min_run_s, max_duration_s
        The shortest run worth importing and the longest a scenario allows [s].
    """

    start_room_m: float
    preview_s: float
    vehicle_length_m: float
    min_run_s: float
    max_duration_s: float

    def min_route_length_m(self, speed_mps: float) -> float:
        """The shortest route a run of ``min_run_s`` at ``speed_mps`` fits on [m]: room behind
        the start, the run, the planner's preview and the body beyond its end."""
        return (self.start_room_m + speed_mps * (self.min_run_s + self.preview_s)
                + self.vehicle_length_m)


def choose_run(road: ImportedRoad, *, speed_mps: float, limits: RunLimits) -> RunChoice:
    """Start at the planning problem's position (at least ``limits.start_room_m`` in; back
    there if the problem's start leaves too little path) and run until the planner's preview at
    ``speed_mps`` plus the body reaches the path's end.

    Raises
    ------
    ValueError
        If the run would last less than ``limits.min_run_s`` (the route is too short).
    """
    start = max(limits.start_room_m, road.start_s_m or 0.0)
    if start - limits.start_room_m + limits.min_route_length_m(speed_mps) > road.length_m:
        start = limits.start_room_m
    room = road.length_m - start - speed_mps * limits.preview_s - limits.vehicle_length_m
    duration = min(limits.max_duration_s, math.floor(10.0 * room / speed_mps) / 10.0)
    if duration < limits.min_run_s:
        raise ValueError(f"{road.route_label}: the route is {road.length_m:.0f} m long, a run at "
                         f"{speed_mps:g} m/s needs at least "
                         f"{limits.min_route_length_m(speed_mps):.0f} m (--length-m, or a lower "
                         "--speed-mps)")
    return RunChoice(round(start, 2), speed_mps, duration)


def clear_of_start(road: ImportedRoad, run: RunChoice, *, vehicle_length_m: float,
                   vehicle_width_m: float) -> ImportedRoad:
    """``road`` without the obstacles that overlap the vehicle's body where it starts (a run
    would begin in a collision); each one dropped gets a message."""
    kept, dropped = [], list(road.dropped)
    for o in road.obstacles:
        if (abs(o.s_m - run.start_s_m) < 0.5 * (vehicle_length_m + o.length_m)
                and abs(o.d_m) < 0.5 * (vehicle_width_m + o.width_m)):
            dropped.append(f"obstacle {o.obstacle_id} at s = {o.s_m:.1f} m, d = {o.d_m:.1f} m: "
                           "overlaps the vehicle at its start")
        else:
            kept.append(o)
    return replace(road, obstacles=tuple(kept), dropped=tuple(dropped))


def _fmt(value: float, digits: int) -> str:
    text = f"{value:.{digits}f}".rstrip("0").rstrip(".")
    return "0.0" if text in ("", "-0") else (text if "." in text else text + ".0")


def road_scenario_toml(road: ImportedRoad, run: RunChoice, *, vehicle: str, mu: float,
                       mu_source: str) -> str:
    """The ``road`` scenario of an imported route as TOML text (the schema of issue 37).

    A symmetric own lane of :attr:`LaneWidths.ego_width_m`, the opposing lane's smallest width,
    one friction value everywhere and the obstacles at their positions at time 0.
    """
    lanes = road.lanes
    nearer = np.minimum(lanes.left_m, lanes.right_m)
    header = [
        f"# Imported from CommonRoad {road.source.name}: {road.route_label}",
        f"# (lanelets {', '.join(map(str, road.lanelet_ids))}).",
        f"# Path: the route's centre line smoothed by commonroad-clcs ({road.smoothing}),",
        f"# resampled every {_fmt(road.s_m[1] - road.s_m[0], 2)} m, relative to the file's point "
        f"({_fmt(road.origin_m[0], 3)}, {_fmt(road.origin_m[1], 3)}) m. Tightest bend "
        f"R {road.smallest_radius_m:.1f} m",
        f"# (circles through points {_fmt(BEND_BASELINE_M, 1)} m apart; through consecutive "
        f"points {road.smallest_vertex_radius_m:.1f} m).",
        f"# Own lane: twice the least distance from the path to the nearer lanelet boundary "
        f"({nearer.min():.2f} m;",
        f"# it ranges {nearer.min():.2f}–{nearer.max():.2f} m). Opposing lane: its least width "
        f"where one is adjacent ({100 * lanes.opposing_coverage:.0f} % of the path).",
        f"# Friction: {mu_source}.",
        "# Written by `mufusion import-commonroad` (docs/commonroad.md).",
    ]
    lines = [
        *header,
        'name = "road"',
        f'description = "CommonRoad {road.source.stem}, {road.route_label}"',
        f'vehicle = "{vehicle}"',
        f"initial_speed_mps = {_fmt(run.initial_speed_mps, 3)}",
        f"duration_s = {_fmt(run.duration_s, 1)}",
        "seed = 0",
        f"start_s_m = {_fmt(run.start_s_m, 2)}",
        "",
        "[path]",
        "points_m = [",
        *(f"  [{_fmt(x, 4)}, {_fmt(y, 4)}]," for x, y in road.points_m),
        "]",
        "",
        "[lanes]",
        f"ego_width_m = {_fmt(lanes.ego_width_m, 3)}",
        f"opposing_width_m = {_fmt(lanes.opposing_width_m, 3)}",
        'drivable = "ego_lane"',
        "",
        "[friction]",
        f"mu = {_fmt(mu, 3)}",
    ]
    for o in road.obstacles:
        lines += ["", f"[[obstacles]]  # CommonRoad obstacle {o.obstacle_id}",
                  f"s_m = {_fmt(o.s_m, 3)}", f"d_m = {_fmt(o.d_m, 3)}",
                  f"length_m = {_fmt(o.length_m, 3)}", f"width_m = {_fmt(o.width_m, 3)}",
                  f"speed_mps = {_fmt(o.speed_mps, 3)}"]
    return "\n".join(lines) + "\n"
