"""A pop-up that appears later appears ``distance_m`` ahead of the vehicle, in the closed loop."""

from __future__ import annotations

import pytest

from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import build_loop, run_loop


def test_a_popup_after_a_cruise_appears_its_distance_ahead_and_is_answered_then() -> None:
    cfg = load_scenario("popup", ["initial_speed_mps=22", "obstacle.distance_m=32",
                                  "obstacle.appear_at_s=1.5", "duration_s=2.0"])
    log = run_loop(build_loop(cfg, friction="GT"), cfg.duration_s)
    ts = log.timeseries
    active = ts[ts["obstacle_active"].astype(bool)]
    first = active.iloc[0]
    # About 1.5 s of cruising at 22 m/s, then the 1 m obstacle's near face 32 − 0.5 m ahead of
    # the front (less one 20 ms tick of travel).
    assert first["t_s"] == pytest.approx(1.5, abs=0.05)
    assert first["clearance_m"] == pytest.approx(31.5, abs=0.5)
    assert not ts["in_collision"].astype(bool).any()
    steps = log.planning_steps
    assert (steps.loc[steps["t_s"] < first["t_s"], "mode"] == "cruise").all()
    assert (steps.loc[steps["t_s"] > first["t_s"], "mode"] != "cruise").all()
