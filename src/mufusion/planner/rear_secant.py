"""The plans' rear tire at the utilisation their guess asks of it.

``PlannerConfig.rear_secant_reserve``, docs/decisions/0121.

The planner's rear tire is linear with the secant stiffness at the utilisation factor λ
(:func:`~mufusion.vehicle.planner_model.rear_cornering_stiffness_n_per_rad`): the force it
predicts at any slip below λ's is at most the Magic Formula's, so a plan never counts on rear
grip the tire cannot give. The price is the slip it predicts for a moderate force: at 0.24 of
the friction the truck's secant at 0.9 (0.60 of the tangent) puts the rear slip, and so the
body's attitude, at 1.6 times the tire's. In a narrow lane that attitude decides how fast the
body fits a curve (:mod:`mufusion.planner.body_fit`): a truck in a 3.0 m lane was asked for
14.3 m/s on a 145 m arc on μ̂ 0.6, and from a fast approach it braked into the arc at its
polygons (docs/decisions/0121).

With a reserve δ each cruising stage's rear tire takes the secant at ``min(λ, u + δ)``, ``u`` the
rear's utilisation the guess asks for: the steady lateral force of its yaw rate,
``m v_x ψ̇ l_f / L``, and its longitudinal force, combined (``hypot``), per ``μ̂ F_zr``. Below
``u + δ`` the tire still gives at least the linear force; the reserve covers a plan that asks
the rear for more than its guess did. Where the guess's speed is so low that the stiffer tire
would outrun the RK4 steps sized for λ's secant (:mod:`mufusion.planner.integration`), the
stiffness stays within what those steps integrate stably. Evading, stopping and the minimal-risk
manoeuvre keep λ's secant: there the rear's demand jumps from one plan to the next.

Off by default: measured, not adopted (docs/decisions/0121).
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from mufusion.planner.ocp import Param
from mufusion.planner.plan import StageParameters
from mufusion.vehicle.params import TireParams, VehicleParams
from mufusion.vehicle.planner_model import (
    MIN_SPEED_FOR_SLIP_MPS,
    Input,
    State,
    secant_stiffness_factor,
)

UTILIZATION_FLOOR = 0.05
"""Lowest utilisation whose secant a stage takes [-] (the curve is all but linear below it)."""
_GRID = np.linspace(0.01, 1.0, 100)


@functools.lru_cache(maxsize=16)
def _factor_table(tire: TireParams) -> np.ndarray:
    table = np.array([secant_stiffness_factor(tire, float(u)) for u in _GRID])
    table.flags.writeable = False
    return table


def secant_factors(tire: TireParams, utilization: np.ndarray) -> np.ndarray:
    """Secant / tangent stiffness of ``tire``'s lateral curve at each ``utilization`` in
    [0.01, 1], interpolated on a table of :func:`secant_stiffness_factor` (100 points).

    >>> from mufusion.vehicle.params import TRUCK
    >>> f = secant_factors(TRUCK.tire, np.array([0.05, 0.5, 0.9]))
    >>> bool(f[0] > f[1] > f[2]), abs(float(f[2]) - secant_stiffness_factor(TRUCK.tire, 0.9)) < 1e-3
    (True, True)
    """
    return np.interp(np.asarray(utilization, dtype=float), _GRID, _factor_table(tire))


def guessed_rear_utilization(
    guess_states: np.ndarray, guess_inputs: np.ndarray, mu_hat: np.ndarray, rear_load_n: np.ndarray,
    params: VehicleParams,
) -> np.ndarray:
    """The rear axle's utilisation per stage 0 … N−1 the guess asks for [-]: its steady lateral
    force ``m v_x ψ̇ l_f / L`` and its longitudinal force, combined, per ``μ̂ F_zr``."""
    x = np.asarray(guess_states, dtype=float)[:-1]
    vx = np.maximum(x[:, State.vx], MIN_SPEED_FOR_SLIP_MPS)
    lateral = (params.mass_kg * vx * x[:, State.psidot] * params.cog_to_front_axle_m
               / params.wheelbase_m)
    grip = np.asarray(mu_hat, dtype=float) * np.asarray(rear_load_n, dtype=float)
    longitudinal = np.asarray(guess_inputs, dtype=float)[:, Input.fxr]
    return np.hypot(lateral, longitudinal) / grip


def with_rear_secant_at_guess(
    stage: StageParameters, guess_states: np.ndarray, guess_inputs: np.ndarray,
    params: VehicleParams, utilization_factor: float, reserve: float,
) -> StageParameters:
    """``stage`` with each stage's rear stiffness the secant at ``min(λ, u + reserve)``
    (:func:`guessed_rear_utilization`, at least :data:`UTILIZATION_FLOOR`), never stiffer than
    ``λ``'s secant times ``max(v_x, 1 m/s) / 1 m/s`` (the RK4 steps' stability at the guess's
    speed), and never softer than ``λ``'s secant (the vehicle's fixed tire only)."""
    tire = params.tire
    u = guessed_rear_utilization(guess_states, guess_inputs, stage.mu_hat, stage.fzr_n, params)
    u = np.minimum(np.maximum(np.nan_to_num(u, nan=utilization_factor) + reserve,
                              UTILIZATION_FLOOR), utilization_factor)
    at_lambda = secant_stiffness_factor(tire, utilization_factor)
    vx = np.maximum(np.asarray(guess_states, dtype=float)[:-1, State.vx], MIN_SPEED_FOR_SLIP_MPS)
    factor = np.minimum(secant_factors(tire, u), at_lambda * vx / MIN_SPEED_FOR_SLIP_MPS)
    c_r = tire.cornering_stiffness_per_load_1_per_rad * factor * stage.fzr_n
    p = stage.p.copy()
    p[:, Param.rear_stiffness] = c_r
    return dataclasses.replace(stage, rear_stiffness_n_per_rad=c_r, p=p)


@functools.lru_cache(maxsize=16)
def secant_fit_table(tire: TireParams, utilization_factor: float,
                     reserve: float) -> tuple[np.ndarray, np.ndarray]:
    """``(g, u)``: ``g(u) = u / f(min(λ, u + reserve))`` on a grid of ``u`` (``f``:
    :func:`secant_factors`), increasing, so that ``u = interp(slip K / μ̂, g, u)`` solves the
    body's fit ``u μ̂ = slip K f(min(λ, u + reserve))`` for the utilisation at which a rear
    tire at its guessed secant slips ``slip`` (``K``: the tangent stiffness per load)."""
    u = np.linspace(0.0, 1.0, 201)
    f = secant_factors(tire, np.minimum(np.maximum(u + reserve, UTILIZATION_FLOOR),
                                        utilization_factor))
    g = u / f
    g.flags.writeable = u.flags.writeable = False
    return g, u
