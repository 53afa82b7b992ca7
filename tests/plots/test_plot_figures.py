"""Static run figures on synthetic logs: files of the right type, contents that match the log."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.plots import (
    force_polygon_vertices,
    plot_fused_estimate,
    plot_lateral_and_speed,
    plot_planned_forces,
    plot_snapshots,
)
from mufusion.plots._common import (
    draw_obstacles,
    footprint_xy,
    obstacle_corners_xy,
    row_at_position,
)
from mufusion.plots.estimate import build_estimate_figure
from mufusion.plots.forces import build_forces_figure
from mufusion.plots.snapshots import build_snapshots_figure
from mufusion.plots.traces import build_traces_figure
from mufusion.sim.records import ObstacleTrace

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _is_png(path: Path) -> bool:
    return path.is_file() and path.stat().st_size > 1000 and path.read_bytes()[:8] == PNG_MAGIC


def _by_gid(ax, gid: str) -> list:
    return [a for a in (*ax.lines, *ax.patches, *ax.collections) if a.get_gid() == gid]


def test_every_static_figure_writes_a_png(saved_log, tmp_path: Path) -> None:
    logs = [saved_log("popup", c) for c in ("GT", "P", "F")]
    assert _is_png(plot_snapshots(logs[1:], [0.0, 2.0, 18.0], tmp_path / "snap.png"))
    assert _is_png(plot_lateral_and_speed(logs, tmp_path / "traces.png"))
    assert _is_png(plot_planned_forces(logs, 0.5, tmp_path / "forces.png"))
    assert _is_png(plot_fused_estimate(logs[2], 0.5, tmp_path / "est.png"))


def test_snapshot_uses_the_row_nearest_the_requested_position(saved_log) -> None:
    log = saved_log("turn", "L")
    ts = log.timeseries
    travelled = ts["s_m"].to_numpy() - log.meta.start_s_m
    for position in (0.0, 15.0, 30.0, 47.3):
        i = row_at_position(log, position)
        assert abs(travelled[i] - position) == pytest.approx(np.min(np.abs(travelled - position)))

    fig = build_snapshots_figure([log], [15.0, 30.0])
    for ax, position in zip(fig.axes[:2], (15.0, 30.0), strict=True):
        row = ts.iloc[row_at_position(log, position)]
        (footprint,) = _by_gid(ax, "footprint")
        corners = footprint.get_xy()[:4]
        assert corners.mean(axis=0) == pytest.approx([row["x_m"], row["y_m"]], abs=1e-9)
        assert ax.get_title() == f"L, s = {position:g} m"
        (plan,) = _by_gid(ax, "plan")
        plan_t = log.plans["t_s"].unique()
        nearest = plan_t[np.argmin(np.abs(plan_t - row["t_s"]))]
        expected = log.plans[log.plans["t_s"] == nearest].sort_values("k")
        assert np.allclose(plan.get_xdata(), expected["x_m"])


def test_snapshot_grid_shape_obstacle_timing_and_collision_tag(saved_log) -> None:
    p = saved_log("popup", "P", collision_at_s=25.0)
    f = saved_log("popup", "F")
    fig = build_snapshots_figure([p, f], [0.0, 2.0, 18.0, 40.0])
    panels = [ax for ax in fig.axes if ax.get_title()]
    assert len(panels) == 8
    # The obstacle appears at t = 0.5 s: absent at s = 0 (t = 0), present at s = 18 m.
    assert not _by_gid(panels[0], "obstacle")
    assert len(_by_gid(panels[2], "obstacle")) == 1
    assert panels[3].get_title() == "P, s = 40 m (collision)"
    assert panels[2].get_title() == "P, s = 18 m"
    assert panels[7].get_title() == "F, s = 40 m"


def test_lateral_and_speed_has_one_line_per_configuration(saved_log) -> None:
    logs = [saved_log("turn", c) for c in ("GT", "L", "P", "F")]
    ax_d, ax_v = build_traces_figure(logs).axes
    for ax in (ax_d, ax_v):
        runs = _by_gid(ax, "run")
        assert [line.get_label() for line in runs] == ["GT", "L", "P", "F"]
    legend = [t.get_text() for t in ax_d.get_legend().get_texts()]
    assert legend[:4] == ["GT", "L", "P", "F"]
    w = logs[0].meta.road.lane_width_m
    levels = {float(line.get_ydata()[0]) for line in ax_d.lines if line.get_gid() != "run"}
    assert {-w / 2, w / 2, 3 * w / 2} <= levels
    assert "[m]" in ax_d.get_ylabel() and "[m/s]" in ax_v.get_ylabel()


def test_lateral_panel_marks_the_obstacle_in_s_d(saved_log) -> None:
    log = saved_log("popup", "F")
    ax_d, _ = build_traces_figure([log]).axes
    obstacle = log.meta.obstacles[0]
    (box,) = [p for p in ax_d.patches if p.get_label().startswith("obstacle")]
    assert box.get_x() + box.get_width() / 2 == pytest.approx(
        obstacle.s_m - log.meta.start_s_m
    )
    assert box.get_height() == pytest.approx(obstacle.width_m)


@settings(max_examples=30, deadline=None)
@given(radius=st.floats(0.0, 1e5), sides=st.integers(3, 64))
def test_force_polygon_vertices_lie_on_the_circle(radius: float, sides: int) -> None:
    vertices = force_polygon_vertices(radius, sides)
    assert vertices.shape == (sides, 2)
    assert np.allclose(np.hypot(vertices[:, 0], vertices[:, 1]), radius)
    edges = np.hypot(*np.diff(np.vstack([vertices, vertices[:1]]), axis=0).T)
    assert np.allclose(edges, 2 * radius * np.sin(np.pi / sides))


def test_force_figure_draws_each_configurations_plan_and_limits(saved_log) -> None:
    logs = [saved_log("turn", c) for c in ("GT", "L", "F")]
    ax = build_forces_figure(logs, 0.0).axes[0]
    points = _by_gid(ax, "planned")
    polygons = _by_gid(ax, "limit_polygon")
    assert len(points) == len(polygons) == len(_by_gid(ax, "true_circle")) == 3
    for log, pts, poly in zip(logs, points, polygons, strict=True):
        plan = log.plans[log.plans["t_s"] == 0.0]
        assert np.allclose(pts.get_xdata(), plan["fyf_n"] / 1e3)
        radius = plan["limit_front_n"].min() / 1e3
        assert np.allclose(np.hypot(poly.get_xdata(), poly.get_ydata()), radius)
        assert len(poly.get_xdata()) == log.meta.planner.polygon_sides + 1
    assert "[kN]" in ax.get_xlabel() and "[kN]" in ax.get_ylabel()


def test_fused_estimate_shows_the_nearest_planning_step(saved_log) -> None:
    log = saved_log("turn", "F")
    ax = build_estimate_figure(log, 1.04).axes[0]
    est = log.estimates[np.isclose(log.estimates["t_s"], 1.0)]
    (mean,) = _by_gid(ax, "mean")
    assert np.allclose(mean.get_ydata(), est["mean"])
    (mu_hat,) = _by_gid(ax, "mu_hat")
    assert np.allclose(mu_hat.get_ydata(), est["mu_hat"])
    assert "t = 1.00 s" in ax.get_title()
    assert _by_gid(ax, "data")


def test_bad_input_is_rejected_with_a_clear_message(saved_log, tmp_path: Path) -> None:
    log = saved_log("turn", "F")
    with pytest.raises(ValueError, match="logs must hold at least one"):
        plot_snapshots([], [0.0], tmp_path / "a.png")
    with pytest.raises(ValueError, match="logs must hold at least one"):
        plot_lateral_and_speed([], tmp_path / "b.png")
    with pytest.raises(ValueError, match="time_s must lie within"):
        plot_planned_forces([log], 99.0, tmp_path / "c.png")
    with pytest.raises(ValueError, match="time_s must lie within"):
        plot_fused_estimate(log, -3.0, tmp_path / "d.png")
    with pytest.raises(ValueError, match="position must lie within"):
        plot_snapshots([log], [500.0], tmp_path / "e.png")
    with pytest.raises(ValueError, match="positions_m must hold"):
        plot_snapshots([log], [], tmp_path / "f.png")
    with pytest.raises(ValueError, match="fused configuration"):
        plot_fused_estimate(saved_log("turn", "L"), 0.0, tmp_path / "g.png")
    with pytest.raises(ValueError, match="sides"):
        force_polygon_vertices(1.0, 2)
    assert not any(tmp_path.glob("*.png"))


def test_footprint_is_the_oriented_rectangle() -> None:
    corners = footprint_xy(1.0, 2.0, np.pi / 2, 4.0, 2.0)
    # Heading +y: the length runs along y, the width along x.
    assert np.ptp(corners[:, 1]) == pytest.approx(4.0)
    assert np.ptp(corners[:, 0]) == pytest.approx(2.0)
    assert corners.mean(axis=0) == pytest.approx([1.0, 2.0])


def test_a_run_that_ended_early_shows_its_last_tick(saved_log, tmp_path: Path) -> None:
    # P collides and its run stops after ~1 s (about 19 m); F goes on to 40 m.
    p = saved_log("popup", "P", duration_s=1.0, collision_at_s=18.0)
    f = saved_log("popup", "F")
    fig = build_snapshots_figure([p, f], [2.0, 40.0])
    late = fig.axes[1]
    (footprint,) = _by_gid(late, "footprint")
    last = p.timeseries.iloc[-1]
    assert footprint.get_xy()[:4].mean(axis=0) == pytest.approx([last["x_m"], last["y_m"]])
    assert late.get_title().startswith("P, s = 40 m (collision)\n(run ended at 19 m)")
    assert fig.axes[3].get_title() == "F, s = 40 m"
    with pytest.raises(ValueError, match="position must lie within"):
        plot_snapshots([p, f], [200.0], tmp_path / "x.png")


def test_a_moving_obstacle_is_drawn_where_it_is_at_that_time(saved_log) -> None:
    import matplotlib.pyplot as plt

    meta = saved_log("turn", "GT").meta
    s0 = 30.0  # on the straight before the turn (x = s there)
    static = ObstacleTrace(s_m=s0, d_m=3.5, length_m=4.0, width_m=2.0, appear_time_s=None,
                           corners_x_m=[32.0, 28.0, 28.0, 32.0],
                           corners_y_m=[4.5, 4.5, 2.5, 2.5])
    oncoming = static.model_copy(update={"speed_mps": -5.0})
    moving_meta = meta.model_copy(update={"obstacles": [oncoming]})
    # At 2 s its centre is at s = 30 − 10 = 20 m: x from 18 to 22, y (d = 3.5) from 2.5 to 4.5.
    corners = obstacle_corners_xy(moving_meta, oncoming, 2.0)
    np.testing.assert_allclose(np.sort(corners[:, 0]), [18.0, 18.0, 22.0, 22.0], atol=1e-9)
    np.testing.assert_allclose(np.sort(corners[:, 1]), [2.5, 2.5, 4.5, 4.5], atol=1e-9)
    # A static one keeps its logged corners at any time.
    np.testing.assert_array_equal(obstacle_corners_xy(meta, static, 2.0)[:, 0],
                                  static.corners_x_m)
    fig, ax = plt.subplots()
    assert draw_obstacles(ax, moving_meta, 2.0) == 1
    (patch,) = _by_gid(ax, "obstacle")
    assert patch.get_xy()[:, 0].min() == pytest.approx(18.0)
    plt.close(fig)


def test_reproduction_figures_are_the_same_files_from_one_worker_or_two(
    saved_log, tmp_path: Path
) -> None:
    from mufusion.plots.run_figures import reproduction_figures

    # Two variants of saved synthetic runs: with two workers each draws one; the files must
    # be the same bytes as one worker draws them in turn.
    run_dirs = {}
    for key in ("popup-paper", "popup-authors"):
        for config in ("GT", "P", "F"):
            run_dirs[(key, config)] = saved_log("popup", config, duration_s=1.0).save(
                tmp_path / "runs" / f"{key}-{config}")
    one = reproduction_figures(run_dirs, tmp_path / "one", gif=False, jobs=1)
    two = reproduction_figures(run_dirs, tmp_path / "two", gif=False, jobs=2)
    assert list(one) == list(two) and len(one) >= 8
    for name, path in one.items():
        assert _is_png(path) and path.read_bytes() == two[name].read_bytes(), name
    with pytest.raises(ValueError, match="jobs"):
        reproduction_figures(run_dirs, tmp_path / "none", jobs=0)
