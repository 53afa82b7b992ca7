"""The plant's float kernels compute bitwise what the reference functions compute.

The reference step below is the plant's scheme written with the record-based functions
(:func:`axle_outputs`, :func:`_chassis_rates`, :func:`tire_forces_scalar`), as the plant
evaluated it before the kernel; both kernels (Python and compiled) must reproduce it exactly,
not approximately.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.axles import axle_outputs, wheel_speeds
from mufusion.vehicle.params import CAR, TRUCK, VehicleParams
from mufusion.vehicle.plant import Plant, _chassis_rates, initial_state
from mufusion.vehicle.plant_kernel import (
    PlantKernel,
    compiled_kernel_available,
    loaded_tire_fx,
    make_kernel,
    unit_tire,
)
from mufusion.vehicle.plant_state import PlantStateVector, state_vector
from mufusion.vehicle.surface_tires import AUTHORS_TIRES, SurfaceTireTable, tire_for_surface
from mufusion.vehicle.tires import tire_forces_scalar

DT_S = 1.0 / 200.0


def _follow(omega0: float, speed1: float, speed0: float, radius: float) -> float:
    return max(omega0 + (speed1 - speed0) / radius, 0.0) if omega0 > 0.0 else 0.0


def _reference_step(x0, cmd, mu_f, mu_r, p: VehicleParams, table) -> PlantStateVector:
    """The plant's step on records: RK4 chassis, then the implicit wheels."""
    radius, inertia, dt = p.wheel_radius_m, p.wheel_inertia_kgm2, DT_S
    u_f0, _, u_r0, _ = wheel_speeds(x0, p)
    tires = (tire_for_surface(mu_f, p.tire, table), tire_for_surface(mu_r, p.tire, table))

    def stage(x):
        u_f, _, u_r, _ = wheel_speeds(x, p)
        front, rear = axle_outputs(
            x, _follow(x0.omega_front_radps, u_f, u_f0, radius),
            _follow(x0.omega_rear_radps, u_r, u_r0, radius), mu_f, mu_r, p, *tires,
        )
        return _chassis_rates(x, front, rear, cmd, p)

    make = PlantStateVector._make
    k1 = stage(x0)
    k2 = stage(make(a + 0.5 * dt * b for a, b in zip(x0, k1, strict=True)))
    k3 = stage(make(a + 0.5 * dt * b for a, b in zip(x0, k2, strict=True)))
    k4 = stage(make(a + dt * b for a, b in zip(x0, k3, strict=True)))
    x1 = make(a + dt / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4)
              for a, b1, b2, b3, b4 in zip(x0, k1, k2, k3, k4, strict=True))
    u_f1, _, u_r1, _ = wheel_speeds(x1, p)
    pred_f = _follow(x0.omega_front_radps, u_f1, u_f0, radius)
    pred_r = _follow(x0.omega_rear_radps, u_r1, u_r0, radius)
    front, rear = axle_outputs(x1, pred_f, pred_r, mu_f, mu_r, p, *tires)
    new = []
    for omega0, predicted, torque, axle, tire in (
        (x0.omega_front_radps, pred_f, x1.torque_front_nm, front, tires[0]),
        (x0.omega_rear_radps, pred_r, x1.torque_rear_nm, rear, tires[1]),
    ):
        fx_plus = tire_forces_scalar(axle.slip_ratio + 1e-5, axle.slip_angle_rad, axle.fz_n,
                                     axle.mu, tire)[0]
        slope = max((fx_plus - axle.fx_n) / 1e-5, 0.0) * radius / axle.slip_speed_mps
        effective = inertia + dt * radius * slope
        drive, brake = max(torque, 0.0), max(-torque, 0.0)
        free = (inertia * omega0 + dt * (drive - radius * axle.fx_n + radius * slope * predicted)
                ) / effective
        hold = dt * brake / effective
        new.append(free - hold if free > hold else free + hold if free < -hold else 0.0)
    return x1._replace(omega_front_radps=new[0], omega_rear_radps=new[1])


def _random_states(rng: np.random.Generator, n: int) -> list[PlantStateVector]:
    states = []
    for _ in range(n):
        x = initial_state(TRUCK, 0.0, 0.0, rng.uniform(-3, 3), rng.uniform(0.0, 25.0))
        x[3:9] += rng.normal(0.0, [1.0, 1.0, 0.5, 8.0, 8.0, 0.2])
        x[6:8] = np.where(rng.random(2) < 0.2, 0.0, x[6:8])  # locked wheels
        x[9:] = rng.normal(0.0, 3000.0, 2)
        states.append(state_vector(x))
    return states


@pytest.mark.parametrize("table", [None, AUTHORS_TIRES])
def test_kernel_axles_equal_the_reference_bitwise(table: SurfaceTireTable | None) -> None:
    rng = np.random.default_rng(3)
    kernel = PlantKernel(TRUCK, DT_S)
    for x in _random_states(rng, 300):
        mu_f, mu_r = rng.uniform(0.1, 1.2, 2).tolist()
        tires = (tire_for_surface(mu_f, TRUCK.tire, table),
                 tire_for_surface(mu_r, TRUCK.tire, table))
        want = axle_outputs(x, x.omega_front_radps, x.omega_rear_radps, mu_f, mu_r, TRUCK,
                            *tires)
        speeds = kernel.wheel_speeds(x.vx_mps, x.vy_mps, x.yaw_rate_radps, x.steer_rad)
        got = kernel.axles(speeds, x.omega_front_radps, x.omega_rear_radps, mu_f, mu_r, *tires)
        assert [tuple(a)[:8] for a in want] == [tuple(a) for a in got]


def test_kernel_tires_equal_the_reference_bitwise() -> None:
    rng = np.random.default_rng(4)
    for _ in range(500):
        kappa, alpha = rng.normal(0.0, 0.2), rng.normal(0.0, 0.2)
        if rng.random() < 0.1:
            kappa, alpha = 1e-14 * kappa, 0.0  # the linear branch
        mu, fz = rng.uniform(0.05, 1.5), rng.uniform(-100.0, 5e4)
        assert unit_tire(kappa, alpha, mu, CAR.tire) == tire_forces_scalar(
            kappa, alpha, 1.0, mu, CAR.tire)
        assert loaded_tire_fx(kappa, alpha, fz, mu, CAR.tire) == tire_forces_scalar(
            kappa, alpha, fz, mu, CAR.tire)[0]


@pytest.mark.parametrize("kernel", ["python", "compiled"])
@pytest.mark.parametrize("table", [None, AUTHORS_TIRES])
def test_plant_steps_equal_the_reference_scheme_bitwise(
    table: SurfaceTireTable | None, kernel: str
) -> None:
    # Steering, traction, braking to a standstill (wheels lock and are held), μ changing.
    x = initial_state(TRUCK, 5.0, -2.0, 0.4, 14.0)
    plant = Plant(TRUCK, x, DT_S, surface_tires=table, kernel=kernel)
    reference = state_vector(x)
    for k in range(2800):
        t = k * DT_S
        command = ActuatorCommand(
            0.08 * math.sin(2.0 * t), -40_000.0 if t > 4.0 else -9000.0 * (t > 2.0),
            6000.0 if t < 2.0 else -60_000.0 * (t > 4.0),
        )
        mu_f, mu_r = (0.8, 0.8) if t < 1.0 else (0.3, 0.8) if t < 3.0 else (0.3, 0.3)
        out = plant.step(command, mu_f, mu_r)
        reference = _reference_step(reference, (command.clipped(TRUCK).steer_rad,
                                                command.clipped(TRUCK).torque_front_nm,
                                                command.clipped(TRUCK).torque_rear_nm),
                                    mu_f, mu_r, TRUCK, table)
        assert plant.state == reference, f"step {k}"
        want = axle_outputs(reference, reference.omega_front_radps, reference.omega_rear_radps,
                            mu_f, mu_r, TRUCK, tire_for_surface(mu_f, TRUCK.tire, table),
                            tire_for_surface(mu_r, TRUCK.tire, table))
        assert (out.front, out.rear) == want
    assert plant.state.vx_mps < 0.5 and plant.state.omega_rear_radps == 0.0


def test_the_install_built_the_compiled_kernel() -> None:
    # `pip install -e .` compiles it; without it every run silently takes the slower path.
    assert compiled_kernel_available()
    assert type(Plant(CAR, initial_state(CAR, 0.0, 0.0, 0.0, 5.0))._kernel) is not PlantKernel


@pytest.mark.parametrize("params", [TRUCK, CAR], ids=lambda p: p.name)
@pytest.mark.parametrize("table", [None, AUTHORS_TIRES])
def test_compiled_kernel_steps_equal_the_python_kernel_bitwise(
    params: VehicleParams, table: SurfaceTireTable | None
) -> None:
    # Random states far from the test drive above: sliding, yawing, locked wheels, drive and
    # brake torques, each μ on its own; the first stage's axles both computed and handed in.
    rng = np.random.default_rng(11)
    python, compiled = make_kernel(params, DT_S, "python"), make_kernel(params, DT_S, "compiled")
    for x in _random_states(rng, 400):
        mu_f, mu_r = rng.uniform(0.1, 1.2, 2).tolist()
        tires = (tire_for_surface(mu_f, params.tire, table),
                 tire_for_surface(mu_r, params.tire, table))
        command: tuple[float, ...] = (float(rng.uniform(-0.3, 0.3)),
                                      *rng.normal(0.0, 5000.0, 2).tolist())
        if rng.uniform() < 0.5:  # with the stability control's yaw moment, braking force and
            # the front axle's lateral share beside its braked wheel
            command = (*command, float(rng.normal(0.0, 2e4)), -abs(float(rng.normal(0.0, 1e4))),
                       float(rng.uniform(0.5, 1.0)))
        speeds = python.wheel_speeds(x.vx_mps, x.vy_mps, x.yaw_rate_radps, x.steer_rad)
        first = python.axles(speeds, x.omega_front_radps, x.omega_rear_radps, mu_f, mu_r, *tires)
        chassis = tuple(x[:6] + x[8:])
        for given in (None, first):
            args = (chassis, x.omega_front_radps, x.omega_rear_radps, command, mu_f, mu_r,
                    *tires, given)
            # repr: exact digits and the sign of zero, not just ==
            assert repr(compiled.step(*args)) == repr(python.step(*args))


def test_an_unknown_kernel_is_refused_by_name() -> None:
    with pytest.raises(ValueError, match="kernel must be one of auto, compiled, python"):
        Plant(CAR, initial_state(CAR, 0.0, 0.0, 0.0, 5.0), kernel="fast")
