"""A CommonRoad file's route as a smoothed, densely sampled reference polyline.

Everything here imports commonroad-io, commonroad-route-planner and commonroad-clcs (the
``commonroad`` extra) inside the functions, so :mod:`mufusion.road` loads without them.

The chain (docs/commonroad.md): the file is read with ``CommonRoadFileReader``; the route is a
planning problem's shortest reference path from the route planner or a start lanelet's chain of
successors merged up to a length; the route's centre line is smoothed by commonroad-clcs's
iterative curve subdivision (``ProcessingOption.CURVE_SUBDIVISION``: on the A9 on-ramp it gives
R 32.5 m where plain resampling gives 11 m and spline smoothing a 2.3 m artefact at the end,
docs/decisions/0059) and its curvilinear frame is the frame every lateral offset and progress
of the import is measured in.
"""

from __future__ import annotations

import logging
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["DEFAULT_SMOOTHING", "SMOOTHINGS", "CommonRoadFile", "Route", "plan_route",
           "read_commonroad"]

INSTALL_HINT = "install the extra: pip install 'mufusion[commonroad]'"

SMOOTHINGS: dict[str, str] = {
    "elastic_band": "ELASTIC_BAND",
    "curve_subdivision": "CURVE_SUBDIVISION",
}
"""The smoothing names the importer accepts → commonroad-clcs ``ProcessingOption`` members
(each with clcs's default parameters)."""
DEFAULT_SMOOTHING = "curve_subdivision"


@dataclass(frozen=True)
class CommonRoadFile:
    """A read scenario file.

    Attributes
    ----------
    path
        The file.
    scenario, problems
        commonroad-io's ``Scenario`` and ``PlanningProblemSet``.
    """

    path: Path
    scenario: Any
    problems: Any

    @property
    def problem_ids(self) -> list[int]:
        """The planning problems' IDs, sorted."""
        return sorted(self.problems.planning_problem_dict)

    @property
    def underground(self) -> str | None:
        """The file's ``location/environment/underground`` label (``"wet"``, ``"ice"``, …) or
        None when the file has none (2018b files never have one)."""
        location = getattr(self.scenario, "location", None)
        environment = getattr(location, "environment", None)
        label = getattr(environment, "underground", None)
        return None if label is None else str(getattr(label, "value", label)).lower()


@dataclass(frozen=True)
class Route:
    """A route through the lanelet network and its curvilinear frame.

    Attributes
    ----------
    label
        What chose it, e.g. ``"planning problem 1"`` or ``"lanelet 84599 onward, 156 m"``.
    lanelet_ids
        The route's lanelets in driving order.
    smoothing
        The clcs processor that smoothed the centre line (:data:`SMOOTHINGS`).
    frame
        commonroad-clcs's ``CurvilinearCoordinateSystem`` of the smoothed centre line.
    start_state
        The planning problem's initial state (None for a lanelet route).
    time_step
        The time step obstacles are read at: the planning problem's initial one, else 0.
    """

    label: str
    lanelet_ids: tuple[int, ...]
    smoothing: str
    frame: Any
    start_state: Any
    time_step: int


def read_commonroad(path: Path) -> CommonRoadFile:
    """Read a CommonRoad scenario file.

    Raises
    ------
    ValueError
        If the file does not exist, is not readable, is not CommonRoad XML, or the
        ``commonroad`` extra is not installed.
    """
    if not path.is_file():
        raise ValueError(f"FILE {str(path)!r} does not exist or is not a file")
    try:
        with path.open("rb") as handle:
            head = handle.read(4096)
    except OSError as err:
        raise ValueError(f"FILE {str(path)!r} is not readable: {err}") from None
    if b"<commonRoad" not in head:
        raise ValueError(f"FILE {str(path)!r} is not a CommonRoad XML file (no <commonRoad> "
                         "element at its start)")
    try:
        with warnings.catch_warnings():  # protobuf's deprecations at import
            warnings.simplefilter("ignore")
            from commonroad.common.file_reader import CommonRoadFileReader
    except ImportError:
        raise ValueError(f"reading CommonRoad files needs commonroad-io: {INSTALL_HINT}") from None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            scenario, problems = CommonRoadFileReader(str(path)).open()
    except Exception as err:  # the reader raises anything from lxml to AssertionError
        raise ValueError(f"FILE {str(path)!r} could not be read as CommonRoad: {err}") from None
    return CommonRoadFile(path, scenario, problems)


def _smoothed_frame(centre_m: np.ndarray, smoothing: str) -> Any:
    """The curvilinear frame of ``centre_m`` smoothed by ``smoothing`` (clcs's defaults)."""
    try:
        from commonroad_clcs.clcs import CurvilinearCoordinateSystem
        from commonroad_clcs.config import CLCSParams, ProcessingOption
        from commonroad_clcs.ref_path_processing.factory import ProcessorFactory
    except ImportError:
        raise ValueError(f"the reference path needs commonroad-clcs: {INSTALL_HINT}") from None
    params = CLCSParams(processing_option=ProcessingOption[SMOOTHINGS[smoothing]])
    with warnings.catch_warnings():  # OSQP (elastic band) warns on every matrix it converts
        warnings.simplefilter("ignore")
        smoothed = ProcessorFactory.create_processor(params)(np.asarray(centre_m, dtype=float))
        return CurvilinearCoordinateSystem(smoothed, params, preprocess_path=False)


def _truncate(centre_m: np.ndarray, length_m: float) -> np.ndarray:
    """The polyline's first ``length_m`` metres (the last point interpolated)."""
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(centre_m, axis=0).T))])
    if s[-1] <= length_m:
        return centre_m
    k = int(np.searchsorted(s, length_m))
    t = (length_m - s[k - 1]) / (s[k] - s[k - 1])
    end = centre_m[k - 1] + t * (centre_m[k] - centre_m[k - 1])
    return np.vstack([centre_m[:k], end])


def _problem_route(file: CommonRoadFile, problem_id: int) -> tuple[np.ndarray, list[int], Any]:
    """The route planner's shortest reference path of a planning problem."""
    try:
        with warnings.catch_warnings():  # SciPy's deprecation of scipy.spatial.kdtree
            warnings.simplefilter("ignore")
            from commonroad_route_planner.reference_path_planner import ReferencePathPlanner
            from commonroad_route_planner.route_planner import RoutePlanner
    except ImportError:
        raise ValueError(f"planning problems need commonroad-route-planner: {INSTALL_HINT}") \
            from None
    problem = file.problems.planning_problem_dict[problem_id]
    network = file.scenario.lanelet_network
    # The planner logs and warns on routine events (survival routes, lane changes).
    logging.getLogger("commonroad_route_planner").setLevel(logging.ERROR)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            routes = RoutePlanner(network, problem).plan_routes()
            ref = ReferencePathPlanner(lanelet_network=network, planning_problem=problem,
                                       routes=routes).plan_shortest_reference_path()
    except Exception as err:  # the planner raises ValueError, IndexError, … on unusable input
        raise ValueError(f"--planning-problem {problem_id}: the route planner found no usable "
                         f"route ({type(err).__name__}: {err})") from None
    return np.asarray(ref.reference_path, dtype=float), list(ref.lanelet_ids), problem


def _lanelet_route(file: CommonRoadFile, chain: list[int], length_m: float
                   ) -> tuple[np.ndarray, list[int]]:
    """The merged centre line of the successor chain starting with ``chain`` (one branch)."""
    from commonroad.scenario.lanelet import Lanelet

    network = file.scenario.lanelet_network
    merged, id_lists = Lanelet.all_lanelets_by_merging_successors_from_lanelet(
        network.find_lanelet_by_id(chain[0]), network, length_m)
    branches: dict[tuple[int, ...], np.ndarray] = {}
    for lanelet, ids in zip(merged, id_lists, strict=True):
        if list(ids[: len(chain)]) != chain[: len(ids)]:
            continue
        # Only the lanelets the first length_m metres reach tell branches apart.
        lengths = np.cumsum([network.find_lanelet_by_id(i).distance[-1] for i in ids])
        used = tuple(ids[: int(np.searchsorted(lengths, length_m)) + 1])
        branches.setdefault(used, lanelet.center_vertices)
    if not branches:
        raise ValueError(f"--lanelet {','.join(map(str, chain))}: these lanelets are not a chain "
                         "of successors")
    if len(branches) > 1:
        listed = "; ".join(",".join(map(str, ids)) for ids in branches)
        raise ValueError(f"--lanelet {','.join(map(str, chain))}: the route branches within "
                         f"{length_m:g} m; name the branch by its lanelets, one of: {listed}")
    (ids, centre), = branches.items()
    return _truncate(np.asarray(centre, dtype=float), length_m), list(ids)


def plan_route(file: CommonRoadFile, *, problem_id: int | None = None,
               lanelet_ids: list[int] | None = None, length_m: float | None = None,
               smoothing: str = DEFAULT_SMOOTHING) -> Route:
    """The route of a planning problem or of a start lanelet, in its smoothed frame.

    Parameters
    ----------
    file
        The read scenario.
    problem_id
        A planning problem's ID (its shortest route to the goal), or
    lanelet_ids
        a start lanelet, optionally followed by the successors to take where the network
        branches, merged up to ``length_m``.
    length_m
        The route's length [m] (required with ``lanelet_ids``; cuts a planning problem's route).
    smoothing
        One of :data:`SMOOTHINGS`.

    Raises
    ------
    ValueError
        Unknown IDs (the message lists the valid ones), neither or both of a planning problem and
        a lanelet, an ambiguous branch, or a route the planner cannot find.
    """
    if smoothing not in SMOOTHINGS:
        raise ValueError(f"--smoothing must be one of {sorted(SMOOTHINGS)}, got {smoothing!r}")
    if (problem_id is None) == (lanelet_ids is None):
        raise ValueError("give either --planning-problem or --lanelet (with --length-m)")
    network = file.scenario.lanelet_network
    problem = None
    if problem_id is not None:
        if problem_id not in file.problems.planning_problem_dict:
            known = ", ".join(map(str, file.problem_ids)) or "none: use --lanelet ID --length-m L"
            raise ValueError(f"--planning-problem {problem_id} is not in the file (its planning "
                             f"problems: {known})")
        centre, ids, problem = _problem_route(file, problem_id)
        if length_m is not None:
            centre = _truncate(centre, length_m)
        label = f"planning problem {problem_id}"
    else:
        assert lanelet_ids is not None  # for mypy: checked above
        unknown = [i for i in lanelet_ids if network.find_lanelet_by_id(i) is None]
        if unknown:
            raise ValueError(f"--lanelet {unknown[0]} is not in the file's lanelet network "
                             f"({len(network.lanelets)} lanelets, IDs "
                             f"{min(la.lanelet_id for la in network.lanelets)}…"
                             f"{max(la.lanelet_id for la in network.lanelets)})")
        if length_m is None:
            raise ValueError("--lanelet needs --length-m (the route's length in metres)")
        centre, ids = _lanelet_route(file, list(lanelet_ids), length_m)
        label = f"lanelet {ids[0]} onward, {length_m:g} m"
    try:
        frame = _smoothed_frame(centre, smoothing)
    except ValueError:  # the extra missing: its own message
        raise
    except Exception as err:  # clcs raises on paths it cannot frame (heading jumps ≥ π/2)
        raise ValueError(f"{label}: its centre line has no curvilinear frame ({err})") from None
    step = 0 if problem is None else int(problem.initial_state.time_step)
    return Route(label, tuple(int(i) for i in ids), smoothing, frame,
                 None if problem is None else problem.initial_state, step)
