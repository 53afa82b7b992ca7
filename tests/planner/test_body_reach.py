"""The lateral corridor's exact body reach (``planner.exact_body_reach``, docs/decisions/0093:
measured, not the default): one geometry for the swing and the curve's bulge, checked against the
body's long sides on a circular lane."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from mufusion.planner.corridor import body_reach_m, lateral_corridor
from mufusion.scenarios import load_scenario
from mufusion.scenarios.config import planner_lane_bounds_m
from mufusion.vehicle.params import CAR, TRUCK
from mufusion.vehicle.planner_model import State


def _side_offsets_m(d_m: float, dpsi_rad: float, kappa_1pm: float, a_front_m: float,
                    a_rear_m: float) -> np.ndarray:
    """Exact lane offsets of 2,001 points along a straight body's long axis: the reference point
    at offset ``d_m`` on a circular lane (left positive), the body turned by ``dpsi_rad``."""
    x = np.linspace(-a_rear_m, a_front_m, 2001)
    px, py = x * np.cos(dpsi_rad), d_m + x * np.sin(dpsi_rad)
    if kappa_1pm == 0.0:
        return py
    radius = 1.0 / kappa_1pm  # the centre at (0, radius): left of the lane for a left curve
    return radius - np.sign(radius) * np.hypot(px, py - radius)


# Radii from 15 m to 10 km and the straight (the reference circle's own arithmetic loses its
# precision on radii near the float range, not the formula).
CURVATURES = st.one_of(st.just(0.0), st.floats(1e-4, 1 / 15), st.floats(-1 / 15, -1e-4))


@given(kappa=CURVATURES, dpsi=st.floats(-0.1, 0.1), d=st.floats(-0.45, 0.45),
       truck=st.booleans())
def test_the_reach_is_the_long_sides_extremes_on_a_circular_lane(kappa, dpsi, d, truck):
    params = TRUCK if truck else CAR
    a_f, a_r = params.cog_to_body_front_m, params.cog_to_body_rear_m
    lowest, highest = body_reach_m(np.array([np.sin(dpsi)]), np.array([kappa]), a_f, a_r)
    offsets = _side_offsets_m(d, dpsi, kappa, a_f, a_r) - d
    # The small-angle lane frame: within 3 cm for the truck on a 15 m radius 0.45 m off the
    # centre (the lane's curvature seen from the offset point, R / (R − d)); exact on a straight.
    tol = 1e-9 if kappa == 0.0 else 0.03
    assert lowest[0] == pytest.approx(min(offsets.min(), 0.0), abs=tol)
    assert highest[0] == pytest.approx(max(offsets.max(), 0.0), abs=tol)


def test_on_a_straight_the_exact_corridor_is_the_default_bit_for_bit():
    rng = np.random.default_rng(93)
    guess = np.zeros((41, 9))
    guess[:, State.s] = np.linspace(0.0, 40.0, 41)
    guess[:, State.dpsi] = rng.uniform(-0.3, 0.3, 41)
    for params in (TRUCK, CAR):
        for kappa in (None, np.zeros(40)):
            default = lateral_corridor(guess, [], -0.35, 0.35, params, 0.5, kappa, 0.1)
            exact = lateral_corridor(guess, [], -0.35, 0.35, params, 0.5, kappa, 0.1,
                                     exact_reach=True)
            assert np.array_equal(default[0], exact[0]) and np.array_equal(default[1], exact[1])


@pytest.mark.parametrize("direction", [1.0, -1.0], ids=["left", "right"])
def test_the_truck_keeps_room_in_a_15_m_hairpin_at_its_turning_attitude(direction):
    # In a tight bend the truck's nose turns out by about l_r |κ| (the rear axle follows the
    # lane, the centre of gravity's velocity points along it): 0.1 rad on 15 m. Counted apart
    # (the default), the ends' swing (3.6 m × 0.1 rad on the inner side) and a centred body's
    # bulge (0.33 m on the outer) leave no room between the scenario's bounds (±0.35 m for the
    # centre); the rear end's own bulge carries it back out of the inner side, and the body fits.
    cfg = load_scenario("turn", ["vehicle=truck"])
    lo_lane, hi_lane = planner_lane_bounds_m(cfg, TRUCK)
    kappa = direction / 15.0
    guess = np.zeros((41, 9))
    guess[:, State.s] = np.linspace(0.0, 40.0, 41)
    guess[:, State.dpsi] = -direction * 0.1  # the nose turned out of the bend
    apart = lateral_corridor(guess, [], lo_lane, hi_lane, TRUCK, 0.5, np.full(40, kappa), 0.1)
    assert np.all(apart[1] - apart[0] == 0.0)  # collapsed to its midpoint
    lo, hi = lateral_corridor(guess, [], lo_lane, hi_lane, TRUCK, 0.5,
                              np.full(40, kappa), 0.1, exact_reach=True)
    assert np.all(hi - lo > 0.05)
    # Every point of the long sides stays in the lane with the reference point anywhere in it.
    for d in (lo[0], hi[0]):
        offsets = _side_offsets_m(d, -direction * 0.1, kappa, TRUCK.cog_to_body_front_m,
                                  TRUCK.cog_to_body_rear_m)
        assert lo_lane - 0.03 <= offsets.min() and offsets.max() <= hi_lane + 0.03
