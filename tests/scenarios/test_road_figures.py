"""A road run gets the single-run figures (top views at positions of its own: the paper's
layouts are the turn's and the pop-up's), its road drawn with its own lane widths."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from mufusion.plots._common import draw_road
from mufusion.plots.run_figures import _snapshot_positions, single_run_figures
from mufusion.scenarios import scenario_from_dict
from mufusion.scenarios.runner import run_scenario

ONE_WAY_BEND = {
    "name": "road", "vehicle": "car", "initial_speed_mps": 10.0, "duration_s": 2.0,
    "start_s_m": 20.0,
    "path": {"segments": [{"kind": "straight", "length_m": 30.0},
                          {"kind": "arc", "radius_m": 40.0, "angle_rad": -0.8},
                          {"kind": "straight", "length_m": 40.0}]},
    "lanes": {"ego_width_m": 3.5, "opposing_width_m": 0.0},
}


def test_a_road_run_gets_top_views_along_its_way(tmp_path: Path) -> None:
    log = run_scenario(scenario_from_dict(ONE_WAY_BEND), "GT")
    travelled = float(log.timeseries["s_m"].iloc[-1]) - log.meta.start_s_m
    positions = _snapshot_positions(log)
    assert len(positions) == 4 and positions[0] == 0.0
    assert travelled - 0.1 <= positions[-1] <= travelled
    figures = single_run_figures(log, tmp_path, gif=False)
    assert {"snapshots", "traces", "forces"} <= set(figures)
    assert all(path.stat().st_size > 0 for path in figures.values())

    # The one-way road: its surface spans the ego lane only, 3.5 m wide.
    ax = Figure().subplots()
    surface = draw_road(ax, log.meta, (log.meta.road.x_m[40], log.meta.road.y_m[40]), 10.0)
    assert surface is not None
    quad = surface.get_paths()[0].vertices[:4]
    assert abs(np.hypot(*(quad[0] - quad[3])) - 3.5) < 1e-6
    assert log.meta.road.opposing_lane_width_m == 0.0
