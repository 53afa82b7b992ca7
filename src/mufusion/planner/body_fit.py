"""The body's fit in its corridor as a bound on the speed reference's curve speeds.

The speed reference (:mod:`~mufusion.planner.speed_profile`) lets a point mass corner at the
polygon's lateral reach ``a = λ cos(π/n)`` of ``μ̂ g``. A vehicle cornering turns its body
against its path: in the steady state its heading to the lane is ``ψ = α_r − l_r κ`` (the
physics oracle's rigid body, docs/decisions/0090), and the plans' own rear tire, linear with the
secant stiffness ``c̄`` (:func:`~mufusion.vehicle.planner_model.rear_cornering_stiffness_n_per_rad`),
gives ``α_r = u μ̂ / c̄`` at the lateral utilisation ``u``. The corridor takes the body's reach at
the plans' heading off the band the lane bounds leave the reference point
(:func:`~mufusion.planner.corridor.lateral_corridor`): a soft-tired truck at the reference's
utilisation in a narrow lane has an empty corridor, the plans brake inside the arc at their
polygons to win back room, and the tail swings over the edge. The reference therefore corners
at no more than the utilisation at which the plans' steady attitude leaves the corridor a
width, ``u ≤ (ψ_fit(κ) + l_r |κ|) c̄(μ̂) / μ̂``, ``ψ_fit`` the largest heading whose reach the
band holds (counted as the corridor counts it), and reads the curvature as ``|κ| · a / u`` where
that binds, so the profile's braking ramps reach the lower curve speed too
(docs/decisions/0097).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable

import numpy as np

from mufusion.planner.corridor import reach_taken_m
from mufusion.planner.rear_secant import secant_fit_table
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import rear_cornering_stiffness_n_per_rad
from mufusion.vehicle.surface_tires import SurfaceTireTable

CURVATURE_GRID_1PM = np.round(np.arange(0.0, 0.1001, 0.0005), 4)
"""Curvatures at which the fitting heading is tabulated [1/m] (radii from 10 m; a sharper
curve reads the 10 m heading)."""
_MAX_HEADING_RAD = 0.25 * math.pi
"""Headings searched for the fit [rad], each way."""

CapOfMuKappa = Callable[[np.ndarray, np.ndarray], np.ndarray]
"""The lateral utilisation cap [-] at each ``(μ̂, κ)`` pair of two equal-shape arrays."""


@functools.lru_cache(maxsize=64)
def fitting_heading_table(params: VehicleParams, band_m: float, exact_reach: bool) -> np.ndarray:
    """The largest heading [rad] (nose into the curve) at which the body's reach, counted as
    the corridor counts it, leaves the reference point's band ``band_m`` [m] (the lane bounds'
    ``d_max − d_min``) a width, at each of :data:`CURVATURE_GRID_1PM`; NaN where no heading does
    (the corridor is empty at any attitude there) or every heading up to π/4 does.

    The search starts at the heading where the body takes least (slightly nose out of a curve,
    where the longer rear end swings no further out than the front end bulges), and goes beyond
    the 0.1 rad up to which :func:`~mufusion.planner.corridor.lateral_corridor` counts a guess's
    swing: the cap keeps the body itself in the band. Cached per vehicle, band and geometry
    (read-only).
    """
    # scipy.optimize (a quarter of a second to import) loads when a planner first builds a
    # table, not with the configuration: a scenario is validated before the heavy stack loads.
    from scipy.optimize import brentq, minimize_scalar

    out = np.full(CURVATURE_GRID_1PM.shape, np.nan)
    for i, kappa in enumerate(CURVATURE_GRID_1PM):
        def excess(psi: float, k: float = float(kappa)) -> float:
            return float(reach_taken_m(np.array([math.sin(psi)]), np.array([k]), params,
                                       exact_reach)[0]) - band_m

        narrowest = float(minimize_scalar(excess, bounds=(-_MAX_HEADING_RAD, _MAX_HEADING_RAD),
                                          method="bounded", options={"xatol": 1e-9}).x)
        if excess(narrowest) < 0.0 < excess(_MAX_HEADING_RAD):
            out[i] = brentq(excess, narrowest, _MAX_HEADING_RAD, xtol=1e-9)
    out.flags.writeable = False
    return out


def body_fit_cap(params: VehicleParams, band_m: float, utilization_factor: float,
                 exact_reach: bool = False,
                 surface_tires: SurfaceTireTable | None = None,
                 secant_reserve: float | None = None) -> CapOfMuKappa:
    """The cap ``u(μ̂, κ)`` at which the plans' steady attitude (their linear rear tire, secant
    at ``utilization_factor``; ``surface_tires``' stiffness at μ̂ where the planner follows a
    table) still leaves the corridor in ``band_m`` a width; 1 where the corridor is empty at any
    attitude (nothing the speed can do) or the tire limits first. ``secant_reserve`` (the
    vehicle's own tire only): the rear tire's secant at ``min(λ, u + reserve)`` instead, as the
    cruising plans take it (:mod:`mufusion.planner.rear_secant`; docs/decisions/0121).

    Examples
    --------
    >>> from mufusion.vehicle.params import CAR, TRUCK
    >>> cap = body_fit_cap(TRUCK, 0.2, 0.9)  # a 3.0 m lane: 2.6 m body, 0.1 m margins
    >>> # ψ_fit = (0.2 − bulge 0.082) / 6.28 = 0.0188, + l_r κ = 0.0553 rad, × 4.23 / μ
    >>> [round(float(u), 3) for u in cap(np.array([0.3, 0.8]), np.array([1 / 60, -1 / 60]))]
    [0.779, 0.292]
    >>> float(body_fit_cap(CAR, 1.5, 0.9)(np.array([1.0]), np.array([1 / 60]))[0])
    1.0
    """
    heading = fitting_heading_table(params, float(band_m), bool(exact_reach))
    l_r = params.cog_to_rear_axle_m
    # The vehicle's own tire: one stiffness per load whatever μ̂ (a table's follows μ̂).
    fixed = (None if surface_tires is not None
             else float(rear_cornering_stiffness_n_per_rad(params, 1.0, utilization_factor)))
    tangent = params.tire.cornering_stiffness_per_load_1_per_rad
    fit = (None if secant_reserve is None or fixed is None
           else secant_fit_table(params.tire, float(utilization_factor), float(secant_reserve)))

    def cap(mu_hat: np.ndarray, curvature_1pm: np.ndarray) -> np.ndarray:
        mu = np.maximum(np.asarray(mu_hat, dtype=float), 1e-3)
        kappa = np.minimum(np.abs(np.asarray(curvature_1pm, dtype=float)),
                           CURVATURE_GRID_1PM[-1])
        slip = np.interp(kappa, CURVATURE_GRID_1PM, heading) + l_r * kappa
        per_load = fixed if fixed is not None else np.asarray(
            rear_cornering_stiffness_n_per_rad(params, np.ones_like(mu), utilization_factor,
                                               mu_hat=mu, table=surface_tires), dtype=float)
        with np.errstate(invalid="ignore"):
            if fit is not None:  # u μ̂ = slip K f(min(λ, u + δ)), solved on its table
                demand = np.where(slip > 0.0, slip * tangent / mu, np.nan)
                u = np.where(demand <= fit[0][-1], np.interp(demand, *fit), np.inf)
            else:
                u = np.where(slip > 0.0, slip * per_load / mu, np.nan)
        return np.where(np.isfinite(u), np.minimum(u, 1.0), 1.0)

    return cap


def body_fitted_curvature(
    curvature_of_s: Callable[[np.ndarray], np.ndarray],
    mu_of_s: Callable[[np.ndarray], np.ndarray],
    cap: CapOfMuKappa,
    accel_fraction: float,
) -> Callable[[np.ndarray], np.ndarray]:
    """``κ(s)`` scaled by ``accel_fraction / cap(μ(s), κ(s))`` where the cap is the lower: a
    profile that corners at ``accel_fraction`` of ``μ g`` on the scaled curvature corners at
    the cap on the road's (its sign kept).

    Examples
    --------
    >>> kappa = body_fitted_curvature(lambda s: np.full(np.shape(s), -0.02),
    ...                               lambda s: np.full(np.shape(s), 0.8),
    ...                               lambda mu, k: np.full(np.shape(mu), 0.6), 0.9)
    >>> [round(float(k), 4) for k in kappa(np.array([0.0, 1.0]))]  # −0.02 · 0.9 / 0.6
    [-0.03, -0.03]
    """

    def fitted(s_m: np.ndarray) -> np.ndarray:
        kappa = np.asarray(curvature_of_s(s_m), dtype=float)
        mu = np.asarray(mu_of_s(s_m), dtype=float) * np.ones_like(kappa)
        limit = np.asarray(cap(mu, kappa), dtype=float)
        return kappa * np.maximum(1.0, accel_fraction / np.maximum(limit, 1e-3))

    return fitted
