"""The minimal-risk manoeuvre's braking beside the lane's lateral acceleration (0114)."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from mufusion.planner.minimal_risk import lane_keeping_braking_mps2, minimal_risk_command
from mufusion.vehicle.params import CAR


@given(speed=st.floats(0.0, 40.0), curvature=st.floats(-0.1, 0.1), available=st.floats(0.1, 10.0))
def test_the_braking_stays_on_the_friction_circle(speed, curvature, available) -> None:
    braking = lane_keeping_braking_mps2(speed, curvature, available)
    lateral = speed**2 * abs(curvature)
    assert 0.0 <= braking <= available * (1 + 1e-12)
    if lateral <= available:  # within the tires the lane takes what it asks, braking the rest
        assert braking == pytest.approx(math.sqrt(available**2 - lateral**2), abs=1e-9)
    else:  # beyond them the manoeuvre never stops braking
        assert braking > 0.0


@given(c=st.floats(0.01, 0.999))
def test_beyond_the_tires_the_split_is_the_least_depth_estimates_minimum(c) -> None:
    # c = a / (v² |κ|): the depth estimate (1 − c sin θ) / cos² θ over the split's angle θ.
    available, speed = 5.0, 10.0
    curvature = available / (c * speed**2)
    braking = lane_keeping_braking_mps2(speed, curvature, available)
    theta_chosen = math.acos(braking / available)
    theta = np.linspace(0.0, math.pi / 2 - 1e-3, 20001)
    depth = (1.0 - c * np.sin(theta)) / np.cos(theta) ** 2
    chosen = (1.0 - c * math.sin(theta_chosen)) / math.cos(theta_chosen) ** 2
    assert chosen <= depth.min() * (1 + 1e-6)


def test_the_split_is_continuous_at_the_tires_edge_and_brakes_harder_further_beyond() -> None:
    available, speed = 4.0, 10.0
    edge = available / speed**2
    assert lane_keeping_braking_mps2(speed, edge * (1 + 1e-9), available) < 0.01 * available
    further = [lane_keeping_braking_mps2(speed, k * edge, available) for k in (1.1, 1.5, 3, 10)]
    assert further == sorted(further) and further[-1] > 0.99 * available


def test_the_command_brakes_where_the_curve_is_beyond_the_friction() -> None:
    # The car at 9.7 m/s in a 40 m curve on μ 0.15 (limits_turn_heldout7's spin): the lane asks
    # 2.35 m/s² of 1.18. Before, the manoeuvre braked with nothing for 8 s.
    x = np.array([0.0, -1.0, 0.1, 0.2, 9.7, -1.0])
    cmd = minimal_risk_command(x, 1 / 40, CAR, 0.15, 0.8)
    braking = -(cmd.torque_front_nm + cmd.torque_rear_nm) / CAR.wheel_radius_m / CAR.mass_kg
    assert braking == pytest.approx(lane_keeping_braking_mps2(9.7, 1 / 40, 0.8 * 0.15 * 9.81))
    assert braking > 0.9


def test_the_command_steers_within_the_front_tires_peak_from_its_axles_course() -> None:
    from mufusion.vehicle.tires import peak_slip_angle_rad

    # Sliding 5 m right of the lane on μ 0.15, the body 0.3 rad out of its path: the feedback
    # asks for a hard left; the front axle moves 0.27 rad to the right of the heading.
    x = np.array([0.0, -5.0, 0.05, 0.2, 6.7, -2.06])
    cmd = minimal_risk_command(x, 1 / 40, CAR, 0.15, 0.8)
    course = math.atan2(-2.06 + CAR.cog_to_front_axle_m * 0.2, 6.7)
    slip_angle = cmd.steer_rad - course
    assert abs(slip_angle) == pytest.approx(peak_slip_angle_rad(CAR.tire, 0.15))
    # Rolling along the lane the cap leaves the feedback alone.
    calm = minimal_risk_command(np.array([0.0, 0.2, 0.01, 0.0, 10.0, 0.0]), 0.0, CAR, 0.9, 0.8)
    assert calm.steer_rad == pytest.approx(-0.05 * 0.2 - 0.8 * 0.01)
