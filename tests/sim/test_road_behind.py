"""The planner's μ̂ behind the centre of gravity: the road the vehicle has passed."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.metrics import compute_metrics
from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import build_loop, run_loop
from mufusion.sim.planning import road_behind
from mufusion.vehicle.params import vehicle_preset

# Ice (0.15) rising to 0.5 inside the 20 m entry clothoid of a 25 m quarter turn, the truck at
# 14 m/s 60 m before it: feasible by 0.96 m/s (docs/decisions/0072).
RISE_IN_THE_CLOTHOID = [
    "vehicle=truck", "initial_speed_mps=14", "turn.radius_m=25", "turn.angle_rad=1.5708",
    "turn.start_ahead_m=60", "turn.clothoid_m=20", "turn.direction=left",
    "friction.mu_before=0.15", "friction.mu_turn=0.5", "friction.change_ahead_m=75",
]


@settings(max_examples=50, deadline=None)
@given(steps=st.lists(st.floats(0.1, 3.0), min_size=1, max_size=12),
       length=st.floats(1.0, 12.0))
def test_each_point_behind_keeps_the_latest_estimate_that_covered_it(
    steps: list[float], length: float
) -> None:
    grid = np.arange(0.0, 51.0)
    truth = lambda s: np.where(np.asarray(s) < 20.0, 0.2, 0.8)  # noqa: E731
    empty = np.empty(0)
    trail: tuple[np.ndarray, np.ndarray] = (empty, empty)
    last = None
    s = 10.0
    for step in steps:
        s += step
        trail = road_behind(trail, last, s, length)
        last = (s + grid, truth(s + grid) + 0.01 * s)  # each step's estimate a little apart
        behind_s, behind_mu = trail
        assert np.all(np.diff(behind_s) > 0)
        assert np.all((behind_s < s) & (behind_s >= s - length))
        # Every point comes from the latest step whose grid held it.
        for point, mu in zip(behind_s, behind_mu, strict=True):
            anchors = [a for a in np.cumsum([10.0, *steps])[:-1] if a <= point]
            assert mu == pytest.approx(truth(point) + 0.01 * max(anchors))


class _Recording:
    """The package's planner, recording μ̂ under the rear axle at each planning step."""

    def __init__(self, planner: Any, rear_m: float) -> None:
        self._planner, self._rear_m, self.seen = planner, rear_m, []

    def step(self, x0: np.ndarray, t_s: float, **kwargs: Any) -> Any:
        s = float(x0[0])
        self.seen.append((s, float(kwargs["mu_hat_of_s"](np.array([s - self._rear_m]))[0])))
        return self._planner.step(x0, t_s, **kwargs)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._planner, name)


def test_the_rear_axle_is_planned_on_the_friction_it_is_on() -> None:
    cfg = load_scenario("turn", [*RISE_IN_THE_CLOTHOID, "duration_s=9"])
    rise_s = cfg.start_s_m + 75.0
    rear_m = vehicle_preset("truck").cog_to_rear_axle_m
    loop = build_loop(cfg, friction="GT")
    loop.planner = recording = _Recording(loop.planner, rear_m)
    log = run_loop(loop, cfg.duration_s)
    straddling = [(s, mu) for s, mu in recording.seen if s - rear_m + 0.5 < rise_s < s - 0.5]
    assert straddling, "no planning step with the rise between the axles"
    assert all(mu == pytest.approx(0.15) for _, mu in straddling)
    # And GT keeps its lane here (0.12 m out when the rear axle was planned on the CoG's 0.5).
    assert not compute_metrics(log).left_lane
