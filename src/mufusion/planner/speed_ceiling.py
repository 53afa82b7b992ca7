"""The speed ceiling: the speed reference as a soft upper bound on each stage's planned speed.

The speed reference (:mod:`mufusion.planner.speed_profile`) is the point mass's highest speed
along the road, its braking ramps using ``braking_fraction`` of the friction. Tracked only in a
least-squares sense, it let each plan rise above a ramp for its first stages — to drive, or just
to hold speed, while the lateral terms gained from it — and catch up at the friction limit
further on; the next plan did the same again, so the vehicle arrived at the curve late on its
ramp with the friction's reserve spent (the truck of the road probe's ``s_entry_a`` at 28.8 m/s
reached a μ 0.25 patch 2.3 m/s above the ramp; docs/decisions/0088). As a ceiling the ramp is
kept.

Off by default (``PlannerConfig.speed_ceiling``): measured, not adopted. The pattern is real,
but from nearby starts GT left its lane on the road probe about as often with the ceiling as
without (53 against 56 of 512 feasible runs) and F-safe twice as often where GT kept it
(docs/decisions/0088).

A vehicle already above the reference (its start, a drop in μ̂) gets a ceiling that comes down
from its own speed with the same braking share: it is asked to brake as the reference's ramps
would, never harder than that share of the friction grants, so the ceiling never demands the
braking that leaves a plan no lateral reserve; the least-squares tracking still pulls it
further down.
"""

from __future__ import annotations

import numpy as np

from mufusion.vehicle.params import GRAVITY_MPS2


def speed_ceiling_mps(
    reference_mps: np.ndarray,
    start_speed_mps: float,
    mu_hat: np.ndarray,
    decel_fraction: float,
    dt_s: float,
) -> np.ndarray:
    """The ceiling of stages 1 … N: the reference, or the descent from the vehicle's speed.

    Parameters
    ----------
    reference_mps
        The speed reference at stages 1 … N [m/s], shape (N,).
    start_speed_mps
        The vehicle's speed at stage 0 [m/s].
    mu_hat
        Friction the planner may use at stages 0 … N−1 [-], shape (N,): stage ``k``'s braking
        brings stage ``k + 1`` down.
    decel_fraction
        Share of ``μ̂ g`` the descent brakes with, in (0, 1] (the reference's braking share of
        the polygon's reach).
    dt_s
        Stage length [s], > 0.

    Returns
    -------
    ndarray
        ``max(reference, v_0 − Σ_{j ≤ k} decel_fraction μ̂_j g dt)`` per stage, shape (N,).

    Examples
    --------
    >>> ref = np.array([19.4, 19.0, 18.6])
    >>> speed_ceiling_mps(ref, 19.5, np.full(3, 0.5), 0.8, 0.1).round(2).tolist()  # on the ramp
    [19.4, 19.0, 18.6]
    >>> speed_ceiling_mps(ref, 25.0, np.full(3, 0.5), 0.8, 0.1).round(2).tolist()  # above it
    [24.61, 24.22, 23.82]
    """
    reference = np.asarray(reference_mps, dtype=float)
    decel = decel_fraction * np.asarray(mu_hat, dtype=float) * GRAVITY_MPS2
    descent = float(start_speed_mps) - np.cumsum(decel) * dt_s
    return np.maximum(reference, descent)
