"""The probing figure marks the probes, the threshold and the local estimate's availability."""

from __future__ import annotations

import numpy as np

from mufusion.plots.probing import build_probing_figure, plot_probing


def test_probing_figure_shades_the_probe_and_states_its_cost(saved_log, tmp_path) -> None:
    log = saved_log("turn", "F-safe")
    ts = log.timeseries
    ts.loc[(ts["t_s"] >= 0.2) & (ts["t_s"] < 0.6), "control_mode"] = "probing"
    fig = build_probing_figure(log)
    spans = [p for ax in fig.axes for p in ax.patches if p.get_gid() == "probing"]
    assert len(spans) == 3  # one per panel
    t, v = ts["t_s"].to_numpy(), ts["speed_mps"].to_numpy()
    cost = np.interp(0.2, t, v) - np.interp(0.6, t, v)
    assert f"the probes cost {cost:.2f} m/s" in fig.axes[0].get_title()
    assert "1 probe;" in fig._suptitle.get_text()
    assert plot_probing(log, tmp_path / "probing.png").is_file()


def test_without_probing_nothing_is_shaded(saved_log) -> None:
    fig = build_probing_figure(saved_log("turn", "F"))
    assert not [p for ax in fig.axes for p in ax.patches if p.get_gid() == "probing"]
    assert "0 probes" in fig._suptitle.get_text()
