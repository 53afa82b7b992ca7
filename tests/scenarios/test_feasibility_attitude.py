"""The oracle's rigid body: the lateral utilisation a body turned by its rear tire's slip angle
can use inside its lane (scenarios/feasibility/attitude.py, docs/decisions/0090)."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.scenarios import load_scenario
from mufusion.scenarios.feasibility import classify_scenario, turn_feasibility
from mufusion.scenarios.feasibility.attitude import BodyInLane, footprint_span_m
from mufusion.vehicle.params import CAR, TRUCK
from mufusion.vehicle.surface_tires import AUTHORS_TIRES, tire_for_surface
from mufusion.vehicle.tires import tire_forces_scalar

LANE_M = 3.5


def test_the_span_is_the_width_straight_and_the_rotated_rectangle_on_a_straight_road() -> None:
    assert footprint_span_m(0.0, 0.0, 2.6, 2.65, 3.63) == pytest.approx(2.6)
    psi = 0.15
    assert footprint_span_m(psi, 0.0, 2.6, 2.65, 3.63) == pytest.approx(
        2.6 * math.cos(psi) + 6.28 * math.sin(psi))
    # A curve's bulge adds to the rear end the attitude swings out (nose into the curve) and
    # the span grows with the attitude.
    assert footprint_span_m(psi, 1 / 80, 2.6, 2.65, 3.63) > footprint_span_m(psi, 0.0, 2.6,
                                                                            2.65, 3.63)
    spans = [footprint_span_m(p, 1 / 40, 2.6, 2.65, 3.63) for p in (0.0, 0.05, 0.1, 0.2)]
    assert spans == sorted(spans)


def test_the_truck_on_a_dry_wide_bend_cannot_use_the_planners_utilisation() -> None:
    """At the cap the rear tire's slip, less what the wheelbase gives back, turns the truck's
    body until it spans the lane exactly; on low friction or a tight bend the cap is 1."""
    body = BodyInLane.of(TRUCK, LANE_M)
    kappa, mu = 1 / 80, 0.9
    cap = body.lateral_cap(mu, kappa)
    assert 0.8 < cap < 0.9
    # The slip angle at which the tire delivers `cap`, found independently by bisection.
    lo, hi = 0.0, 0.4
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        used = tire_forces_scalar(0.0, mid, 1.0, mu, TRUCK.tire)[2]
        lo, hi = (mid, hi) if used < cap else (lo, mid)
    heading = lo - TRUCK.cog_to_rear_axle_m * kappa
    span = footprint_span_m(heading, kappa, TRUCK.width_m, TRUCK.cog_to_body_front_m,
                            TRUCK.cog_to_body_rear_m)
    assert span == pytest.approx(LANE_M, abs=1e-3)
    assert body.lateral_cap(0.3, kappa) == 1.0  # the tire peaks before the body fills the lane
    assert body.lateral_cap(0.9, 1 / 15) > 0.95  # l_r κ gives back most of the slip
    # More friction, more slip at the same utilisation: the cap falls with μ.
    assert body.lateral_cap(1.0, kappa) < cap < body.lateral_cap(0.6, kappa)


def test_the_cars_stiff_tire_never_turns_its_body_out_of_the_lane() -> None:
    body = BodyInLane.of(CAR, LANE_M)
    assert all(body.lateral_cap(mu, 1 / r) == 1.0
               for mu in (0.2, 0.6, 1.0) for r in (15.0, 40.0, 150.0))


def test_a_body_that_does_not_fit_straight_may_fit_nose_out_of_a_tight_bend() -> None:
    """The truck in a 3.0 m lane on a 15 m radius: aligned with the lane at its centre of
    gravity its rear end sticks out (3.04 m), turned slightly nose out of the bend it fits, so
    the cap is the slip at which it spans the lane again, not 1 (docs/decisions/0097)."""
    lane, kappa = 3.0, 1 / 15
    geometry = (TRUCK.width_m, TRUCK.cog_to_body_front_m, TRUCK.cog_to_body_rear_m)
    assert footprint_span_m(0.0, kappa, *geometry) > lane
    assert footprint_span_m(-0.05, kappa, *geometry) < lane
    body = BodyInLane.of(TRUCK, lane)
    cap = body.lateral_cap(0.8, kappa)
    assert 0.5 < cap < 1.0
    lo, hi = 0.0, 0.4  # the slip at which the tire delivers `cap`, by bisection
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        used = tire_forces_scalar(0.0, mid, 1.0, 0.8, TRUCK.tire)[2]
        lo, hi = (mid, hi) if used < cap else (lo, mid)
    heading = lo - TRUCK.cog_to_rear_axle_m * kappa
    assert -0.05 < heading < 0.0
    assert footprint_span_m(heading, kappa, *geometry) == pytest.approx(lane, abs=1e-3)


def test_a_surface_dependent_tire_is_judged_at_the_surfaces_own_stiffness() -> None:
    """The authors' tire set is stiffer on dry asphalt than the truck's own: less slip, a
    higher cap."""
    own = BodyInLane.of(TRUCK, LANE_M)
    table = BodyInLane.of(TRUCK, LANE_M,
                          lambda mu: tire_for_surface(mu, TRUCK.tire, AUTHORS_TIRES))
    assert table.lateral_cap(0.9, 1 / 80) > own.lateral_cap(0.9, 1 / 80)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(radius=st.sampled_from([15.0, 40.0, 80.0, 150.0]),
       mu=st.sampled_from([0.3, 0.6, 0.9, 1.0]),
       speed=st.floats(10.0, 30.0),
       start=st.floats(10.0, 80.0))
def test_the_body_never_makes_a_turn_easier_and_leaves_the_cars_alone(radius, mu, speed,
                                                                      start) -> None:
    def verdict(vehicle, body):
        return turn_feasibility(
            entry_speed_mps=speed, radius_m=radius, turn_angle_rad=math.pi / 2,
            turn_start_ahead_m=start, clothoid_m=5.0, mu_before=mu, mu_turn=mu,
            friction_change_ahead_m=0.0, utilization_factor=0.9, dead_time_s=0.15,
            lane_width_m=LANE_M, vehicle_width_m=vehicle.width_m,
            vehicle_length_m=vehicle.length_m, body=body)

    for vehicle in (TRUCK, CAR):
        point, rigid = verdict(vehicle, None), verdict(vehicle, BodyInLane.of(vehicle, LANE_M))
        assert rigid.margin_mps <= point.margin_mps + 1e-9
        assert rigid.feasibility_class.rank <= point.feasibility_class.rank
    car = verdict(CAR, BodyInLane.of(CAR, LANE_M))
    assert car.margin_mps == verdict(CAR, None).margin_mps


def test_the_scenario_oracle_judges_the_trucks_body() -> None:
    """A truck 20 m/s onto a dry 150 m bend: the body takes about a metre per second off the
    speed the point mass would grant (classify_scenario passes the vehicle's body)."""
    overrides = ["vehicle=truck", "turn.radius_m=150", "initial_speed_mps=20",
                 "friction.mu_before=0.3", "friction.mu_turn=0.9", "friction.change_ahead_m=10"]
    cfg = load_scenario("turn", overrides)
    rigid = classify_scenario(cfg, TRUCK)
    point = turn_feasibility(
        entry_speed_mps=20.0, radius_m=150.0, turn_angle_rad=cfg.turn.angle_rad,
        turn_start_ahead_m=cfg.turn.start_ahead_m, clothoid_m=cfg.turn.clothoid_m,
        mu_before=0.3, mu_turn=0.9, friction_change_ahead_m=10.0,
        utilization_factor=cfg.planner.utilization_factor,
        dead_time_s=TRUCK.torque_time_constant_s, lane_width_m=cfg.road.lane_width_m,
        vehicle_width_m=TRUCK.width_m, vehicle_length_m=TRUCK.length_m,
        max_decel_mps2=(TRUCK.max_brake_torque_front_nm + TRUCK.max_brake_torque_rear_nm)
        / (TRUCK.wheel_radius_m * TRUCK.mass_kg),
        front_axle_ahead_m=TRUCK.cog_to_front_axle_m,
        rear_axle_behind_m=TRUCK.cog_to_rear_axle_m)
    assert 0.3 < point.margin_mps - rigid.margin_mps < 1.5
