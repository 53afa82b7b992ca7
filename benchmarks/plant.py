"""Plant integration speed: 10 s at 200 Hz, against CommonRoad's STD model in the same run, and
the compiled plant kernel against the Python one (bitwise the same steps).

Run: ``python benchmarks/plant.py``. Prints wall times and ratios; numbers go to
docs/performance.md, section "## Plant".
"""

from __future__ import annotations

import math
import time

import numpy as np
from vehiclemodels.init_std import init_std
from vehiclemodels.parameters_vehicle2 import parameters_vehicle2
from vehiclemodels.vehicle_dynamics_std import vehicle_dynamics_std

from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import CAR, TRUCK
from mufusion.vehicle.plant import Plant, initial_state, plant_derivative
from mufusion.vehicle.plant_kernel import compiled_kernel_available

DT_S = 1.0 / 200.0
STEPS = 2000  # 10 s
REPEATS = 5


def _best(fn) -> float:
    times = []
    for _ in range(REPEATS):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def run_plant(params, kernel: str = "auto") -> None:
    plant = Plant(params, initial_state(params, 0.0, 0.0, 0.0, 15.0), DT_S, kernel=kernel)
    for k in range(STEPS):
        t = k * DT_S
        brake = -2_000.0 * params.mass_kg / 1000.0 if t > 5.0 else 0.0
        plant.step(ActuatorCommand(0.03 * math.sin(t), brake, 0.0), 0.8, 0.8)


def run_std(substeps: int) -> None:
    p = parameters_vehicle2()
    x = init_std([0.0, 0.0, 0.0, 15.0, 0.0, 0.0, 0.0], p)
    h = DT_S / substeps
    for k in range(STEPS):
        t = k * DT_S
        u = [0.03 * math.cos(t), -2.0 if t > 5.0 else 0.0]
        for _ in range(substeps):
            k1 = vehicle_dynamics_std(list(x), u, p)
            k2 = vehicle_dynamics_std([a + 0.5 * h * b for a, b in zip(x, k1, strict=True)], u, p)
            k3 = vehicle_dynamics_std([a + 0.5 * h * b for a, b in zip(x, k2, strict=True)], u, p)
            k4 = vehicle_dynamics_std([a + h * b for a, b in zip(x, k3, strict=True)], u, p)
            x = [
                a + h / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4)
                for a, b1, b2, b3, b4 in zip(x, k1, k2, k3, k4, strict=True)
            ]


def main() -> None:
    print(f"10 s at {1 / DT_S:.0f} Hz ({STEPS} steps), best of {REPEATS}")
    ours = {}
    kinds = ("compiled", "python") if compiled_kernel_available() else ("python",)
    for params in (TRUCK, CAR):
        for kind in kinds:
            ours[params.name, kind] = _best(lambda p=params, k=kind: run_plant(p, k))
            per_step = ours[params.name, kind] / STEPS * 1e6
            print(f"  mufusion Plant ({params.name}, RK4 + implicit wheels, {kind} kernel): "
                  f"{ours[params.name, kind]:.3f} s  ({per_step:.1f} µs/step)")
        if len(kinds) == 2:
            print(f"  ratio compiled / python kernel ({params.name}): "
                  f"{ours[params.name, 'compiled'] / ours[params.name, 'python']:.2f}")
    ours["car"] = ours["car", kinds[0]]
    std_1 = _best(lambda: run_std(1))
    std_5 = _best(lambda: run_std(5))
    print(f"  CommonRoad STD, RK4 1 step per 5 ms:  {std_1:.3f} s  "
          f"({std_1 / STEPS * 1e6:.1f} µs/step)  [wheel modes unresolved: wheel slip off ~1 m/s]")
    print(f"  CommonRoad STD, RK4 5 steps per 5 ms: {std_5:.3f} s  "
          f"({std_5 / STEPS * 1e6:.1f} µs/step)  [converged]")
    print(f"  ratio ours(car) / STD 1 substep:  {ours['car'] / std_1:.2f}")
    print(f"  ratio ours(car) / STD 5 substeps: {ours['car'] / std_5:.2f}")

    x = initial_state(CAR, 0.0, 0.0, 0.0, 15.0)
    command = np.array([0.02, 0.0, 0.0])
    calls = 20_000
    start = time.perf_counter()
    for _ in range(calls):
        plant_derivative(x, command, 0.8, 0.8, CAR)
    ours_call = (time.perf_counter() - start) / calls
    p = parameters_vehicle2()
    xs = init_std([0.0, 0.0, 0.02, 15.0, 0.0, 0.0, 0.0], p)
    start = time.perf_counter()
    for _ in range(calls):
        vehicle_dynamics_std(list(xs), [0.0, 0.0], p)
    std_call = (time.perf_counter() - start) / calls
    print(f"  one derivative call: plant_derivative (numpy in/out) {ours_call * 1e6:.1f} µs, "
          f"vehicle_dynamics_std {std_call * 1e6:.1f} µs, ratio {ours_call / std_call:.2f}")


if __name__ == "__main__":
    main()
