"""The braking two axles reach while cornering (pitch load transfer), against a force balance in
newtons written out per axle, and its effect on the speed reference."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.planner.axle_reach import PitchTransfer, two_axle_braking_mps2
from mufusion.planner.speed_profile import curve_speed_reference_mps, max_speed_profile_mps
from mufusion.vehicle.params import CAR, GRAVITY_MPS2, TRUCK, VehicleParams


def _split_exists(params: VehicleParams, friction: float, lateral_mps2: float,
                  decel_mps2: float) -> bool:
    """Whether some split of ``m d`` between the axles keeps both within ``friction`` times
    their loads beside the steady turn's lateral forces (newtons, from the vehicle's mass)."""
    m, lf, lr, h = (params.mass_kg, params.cog_to_front_axle_m, params.cog_to_rear_axle_m,
                    params.cog_height_m)
    wheelbase = lf + lr
    load_front = m * (GRAVITY_MPS2 * lr + decel_mps2 * h) / wheelbase
    load_rear = m * (GRAVITY_MPS2 * lf - decel_mps2 * h) / wheelbase
    lateral_front = m * lateral_mps2 * lr / wheelbase  # moment balance about the CoG
    lateral_rear = m * lateral_mps2 * lf / wheelbase
    if load_rear <= 0.0:
        return False
    left_front = (friction * load_front) ** 2 - lateral_front**2
    left_rear = (friction * load_rear) ** 2 - lateral_rear**2
    if left_front < 0.0 or left_rear < 0.0:
        return False
    return m * decel_mps2 <= math.sqrt(left_front) + math.sqrt(left_rear)


@settings(max_examples=300, deadline=None)
@given(vehicle=st.sampled_from([TRUCK, CAR]), friction=st.floats(0.05, 1.1),
       lateral_share=st.floats(0.0, 0.999))
def test_the_reach_is_the_largest_deceleration_a_split_of_the_forces_allows(
    vehicle, friction, lateral_share
) -> None:
    accel = friction * GRAVITY_MPS2
    lateral = lateral_share * accel
    reach = two_axle_braking_mps2(accel, lateral, PitchTransfer.of(vehicle))
    assert 0.0 <= reach <= math.sqrt(accel**2 - lateral**2) * (1 + 1e-12)
    assert _split_exists(vehicle, friction, lateral, reach * (1 - 1e-7))
    if reach < math.sqrt(accel**2 - lateral**2) * (1 - 1e-6):
        # Below the point mass's, the axles are what stops it: a little more is out of reach.
        assert not _split_exists(vehicle, friction, lateral, reach * (1 + 1e-6) + 1e-9)


def test_the_truck_brakes_less_than_the_point_mass_where_it_corners_hard() -> None:
    # Module docstring's figures: a/g 0.9, half and 0.7 of the lateral reach.
    truck, car = PitchTransfer.of(TRUCK), PitchTransfer.of(CAR)
    a = 0.9 * GRAVITY_MPS2
    assert two_axle_braking_mps2(a, 0.5 * a, truck) / a == pytest.approx(0.671, abs=1e-3)
    assert two_axle_braking_mps2(a, 0.7 * a, truck) / a == pytest.approx(0.402, abs=1e-3)
    assert two_axle_braking_mps2(a, 0.5 * a, car) / a == pytest.approx(0.833, abs=1e-3)
    assert two_axle_braking_mps2(a, 0.7 * a, car) / a == pytest.approx(0.629, abs=1e-3)
    # Without cornering the whole circle; at the lateral limit nothing; no height, the circle.
    assert two_axle_braking_mps2(a, 0.0, truck) == a
    assert two_axle_braking_mps2(a, a, truck) == 0.0
    assert two_axle_braking_mps2(a, -0.5 * a, truck) == two_axle_braking_mps2(a, 0.5 * a, truck)
    flat = PitchTransfer(TRUCK.cog_to_rear_axle_m / TRUCK.wheelbase_m, 0.0)
    assert two_axle_braking_mps2(a, 0.6 * a, flat) == pytest.approx(0.8 * a, rel=1e-9)


@settings(max_examples=100, deadline=None)
@given(friction=st.floats(0.05, 1.1), low=st.floats(0.0, 0.99), high=st.floats(0.0, 0.99))
def test_more_cornering_leaves_no_more_braking(friction, low, high) -> None:
    low, high = sorted((low, high))
    a = friction * GRAVITY_MPS2
    truck = PitchTransfer.of(TRUCK)
    assert two_axle_braking_mps2(a, high * a, truck) <= two_axle_braking_mps2(a, low * a, truck)


def test_bad_geometry_is_refused_with_its_name() -> None:
    with pytest.raises(ValueError, match="front_share"):
        PitchTransfer(1.0, 0.3)
    with pytest.raises(ValueError, match="height_per_wheelbase"):
        PitchTransfer(0.6, -0.1)


def test_the_truck_reference_brakes_for_a_curve_before_its_clothoid() -> None:
    # A 30 m clothoid into R 50 m from 60 m ahead on μ̂ 0.83: the ramp on the clothoid, where
    # the truck corners while it brakes, is the axles'; on the straight before it, the same.
    def curvature(s):
        s = np.asarray(s, dtype=float)
        return np.clip((s - 60.0) / 30.0, 0.0, 1.0) / 50.0

    def mu(s):
        return 0.83 + 0.0 * np.asarray(s, dtype=float)

    stages = np.linspace(0.0, 150.0, 41)
    refs = {transfer is not None: curve_speed_reference_mps(
        stages, curvature, mu, 30.0, 0.87, 4.0, 0.8, transfer=transfer)
        for transfer in (None, PitchTransfer.of(TRUCK))}
    assert np.all(refs[True] <= refs[False] + 1e-12)
    on_clothoid = (stages > 62.0) & (stages < 88.0)
    assert np.all(refs[True][on_clothoid] < refs[False][on_clothoid] - 0.05)
    # The arc's own speed is the cornering limit either way.
    arc = stages >= 95.0
    np.testing.assert_allclose(refs[True][arc], refs[False][arc])
    # The point mass's profile is what it was without a transfer (the off switch is exact).
    s = np.arange(0.0, 120.0)
    np.testing.assert_array_equal(
        max_speed_profile_mps(s, curvature(s), mu(s), 0.87, 30.0, 0.8),
        max_speed_profile_mps(s, curvature(s), mu(s), 0.87, 30.0, 0.8, None))
