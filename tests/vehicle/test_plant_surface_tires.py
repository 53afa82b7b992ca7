"""The plant with surface-dependent tires: each axle's tire follows the μ under that axle."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import TRUCK
from mufusion.vehicle.plant import Plant, PlantState, axle_forces, initial_state, plant_derivative
from mufusion.vehicle.surface_tires import (
    AUTHORS_TIRES,
    AUTHORS_TIRES_INTERPOLATED,
    lateral_force_n,
    tire_for_surface,
)
from mufusion.vehicle.tires import tire_forces_scalar


def _sliding_state(vy_mps: float = 0.4) -> np.ndarray:
    # Wheels rolling freely (κ = 0) and a lateral velocity: pure lateral slip on both axles.
    x = initial_state(TRUCK, 0.0, 0.0, 0.0, 12.0)
    x[PlantState.VY] = vy_mps
    return x


@pytest.mark.parametrize("table", [AUTHORS_TIRES, AUTHORS_TIRES_INTERPOLATED])
def test_each_axle_gets_the_authors_formula_for_the_mu_under_it(table) -> None:
    front, rear = axle_forces(_sliding_state(), 0.8, 0.4, TRUCK, table)
    assert front.slip_ratio == 0.0 and rear.slip_ratio == 0.0
    for axle, mu in ((front, 0.8), (rear, 0.4)):
        expected = lateral_force_n(axle.slip_angle_rad, axle.fz_n, mu, table)
        assert axle.fy_n == pytest.approx(float(expected), rel=1e-12)
    # The default tire gives other forces for the same slips (7 /rad instead of 22 and 4).
    default_front, default_rear = axle_forces(_sliding_state(), 0.8, 0.4, TRUCK)
    assert abs(front.fy_n) > abs(default_front.fy_n)
    assert abs(rear.fy_n) < abs(default_rear.fy_n)


def test_no_table_is_the_default_tire_in_every_entry_point() -> None:
    x = _sliding_state()
    cmd = ActuatorCommand(0.05, -2e3, 1e3)
    assert axle_forces(x, 0.8, 0.4, TRUCK) == axle_forces(x, 0.8, 0.4, TRUCK, None)
    np.testing.assert_array_equal(plant_derivative(x, cmd, 0.8, 0.4, TRUCK),
                                  plant_derivative(x, cmd, 0.8, 0.4, TRUCK, None))
    a, b = Plant(TRUCK, x), Plant(TRUCK, x, surface_tires=None)
    for _ in range(20):
        out_a, out_b = a.step(cmd, 0.8, 0.4), b.step(cmd, 0.8, 0.4)
    np.testing.assert_array_equal(out_a.x, out_b.x)


def test_plant_step_evaluates_each_axle_with_its_surface_tire() -> None:
    plant = Plant(TRUCK, _sliding_state(), surface_tires=AUTHORS_TIRES)
    cmd = ActuatorCommand(0.03, -5e3, -3e3)  # combined slip on both axles
    for _ in range(40):
        out = plant.step(cmd, 0.8, 0.4)
    for axle, mu in ((out.front, 0.8), (out.rear, 0.4)):
        tire = tire_for_surface(mu, TRUCK.tire, AUTHORS_TIRES)
        fx, fy, used, _ = tire_forces_scalar(axle.slip_ratio, axle.slip_angle_rad, axle.fz_n,
                                             mu, tire)
        assert (axle.fx_n, axle.fy_n, axle.utilization) == pytest.approx((fx, fy, used),
                                                                          rel=1e-12)
        assert axle.slip_ratio != 0.0


def test_derivative_and_step_agree_on_the_surface_tires() -> None:
    # The RK4 chassis step of a tiny dt follows the pure derivative (same tires per axle).
    x = _sliding_state()
    cmd = ActuatorCommand(0.0, 0.0, 0.0)
    xd = plant_derivative(x, cmd, 0.8, 0.4, TRUCK, AUTHORS_TIRES)
    plant = Plant(TRUCK, x, dt_s=1e-5, surface_tires=AUTHORS_TIRES)
    x1 = plant.step(cmd, 0.8, 0.4).x
    rate = (x1 - x) / 1e-5
    for index in (PlantState.VY, PlantState.YAW_RATE):
        assert rate[index] == pytest.approx(xd[index], rel=1e-3)


@pytest.mark.parametrize("mu", [0.4, 0.8])
def test_steady_cornering_slip_angles_scale_with_the_inverse_stiffness(mu) -> None:
    # Independent reference: the linear single-track model. With the stiffness per unit load
    # equal on both axles and static loads, the truck is neutral-steer: the steady yaw rate is
    # v δ / L whatever the stiffness, and each slip angle is a_y / (k g). So the same steering
    # gives the same cornering, and the slip angles scale as the default tire's k over the
    # surface set's (7 /rad against 4 on snow, 22.08 on the authors' μ 0.8 set).
    speed, steer = 10.0, 0.02
    results = {}
    for table in (None, AUTHORS_TIRES):
        plant = Plant(TRUCK, initial_state(TRUCK, 0.0, 0.0, 0.0, speed), surface_tires=table)
        for _ in range(800):  # 4 s: the yaw mode has settled
            out = plant.step(ActuatorCommand(steer, 0.0, 0.0), mu, mu)
        results[table] = out
    default, authors = results[None], results[AUTHORS_TIRES]
    yaw_rate = speed * steer / TRUCK.wheelbase_m
    for out in (default, authors):
        assert out.x[PlantState.YAW_RATE] == pytest.approx(yaw_rate, rel=0.05)
    ratio = TRUCK.tire.cornering_stiffness_per_load_1_per_rad / (
        tire_for_surface(mu, TRUCK.tire, AUTHORS_TIRES).cornering_stiffness_per_load_1_per_rad
    )
    measured = authors.front.slip_angle_rad / default.front.slip_angle_rad
    assert measured == pytest.approx(ratio, rel=0.1)


def test_plant_rejects_a_table_of_the_wrong_type() -> None:
    with pytest.raises(ValueError, match="surface_tires"):
        Plant(TRUCK, _sliding_state(), surface_tires="authors")  # type: ignore[arg-type]
