"""The road under the axles: the speed reference's friction and curvature at the centre of gravity
taken as the worst from the rear axle to the front one (and one torque lag further).

The reference's ramps brake towards the friction and curvature at each point of the centre of
gravity's path; the axles meet a drop or a curve before (the front) and after (the rear) it,
and a brake torque commanded at one point lands one torque lag later (docs/decisions/0055,
0066).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


def lowest_under_axles(
    mu_hat_of_s: Callable[[np.ndarray], np.ndarray], behind_m: float, ahead_m: float
) -> Callable[[np.ndarray], np.ndarray]:
    """``μ̂(s)`` replaced by the lowest estimate from ``behind_m`` behind to ``ahead_m`` ahead of
    ``s`` [m] (at those two points and at ``s``).

    For the speed reference with ``s`` the centre of gravity's: where the friction drops, the
    front axle meets the drop l_f before the CoG does, and a brake torque commanded for the
    higher friction is still being applied one torque lag later. A reference that braked at the
    CoG's friction asked for the high friction's deceleration up to the drop, and the front
    wheels reached the low friction at that torque and locked (docs/decisions/0055).

    Examples
    --------
    >>> mu = lowest_under_axles(lambda s: np.where(np.asarray(s) < 10.0, 0.9, 0.3), 1.5, 2.0)
    >>> mu(np.array([7.0, 8.5, 11.0, 12.0])).tolist()
    [0.9, 0.3, 0.3, 0.3]
    """

    def lowest(s_m: np.ndarray) -> np.ndarray:
        s = np.asarray(s_m, dtype=float)
        return np.minimum(np.minimum(mu_hat_of_s(s - behind_m), mu_hat_of_s(s)),
                          mu_hat_of_s(s + ahead_m))

    return lowest


def sharpest_under_axles(
    curvature_of_s: Callable[[np.ndarray], np.ndarray], behind_m: float, ahead_m: float
) -> Callable[[np.ndarray], np.ndarray]:
    """``κ(s)`` replaced by the sharpest curvature (largest ``|κ|``, its sign kept) from
    ``behind_m`` behind to ``ahead_m`` ahead of ``s`` [m] (at those two points and at ``s``).

    :func:`lowest_under_axles` for the road's curvature: with ``s`` the centre of gravity's, a
    reference that reaches a curve's speed only where the centre of gravity enters it still
    brakes while the front axle turns in, and a brake torque commanded at its end lands one
    torque lag later, inside the curve. Braking while turning in at the curve's limit speed
    unloads the rear axle the curve needs (docs/decisions/0066).

    Examples
    --------
    >>> kappa = sharpest_under_axles(lambda s: np.where(np.asarray(s) < 10.0, 0.0, -0.05),
    ...                              1.5, 4.0)
    >>> kappa(np.array([5.0, 6.5, 11.0, 12.0])).tolist()
    [0.0, -0.05, -0.05, -0.05]
    """

    def sharpest(s_m: np.ndarray) -> np.ndarray:
        s = np.asarray(s_m, dtype=float)
        candidates = np.stack([np.asarray(curvature_of_s(s + offset), dtype=float)
                               * np.ones_like(s) for offset in (-behind_m, 0.0, ahead_m)])
        return np.take_along_axis(candidates, np.abs(candidates).argmax(axis=0)[None], 0)[0]

    return sharpest


def lowest_ahead(mu_hat_of_s: Callable[[np.ndarray], np.ndarray], s_m: np.ndarray,
                 reach_m: np.ndarray) -> np.ndarray:
    """The lowest μ̂ from each ``s_m`` to ``reach_m`` further [m] (at both ends and the middle).

    For the front axle over one torque lag: braking planned at the polygons' μ̂ with the front
    axle just short of a drop lands on the low friction (docs/decisions/0064).

    Examples
    --------
    >>> mu = lambda s: np.where(np.asarray(s) < 10.0, 0.9, 0.3)
    >>> lowest_ahead(mu, np.array([8.0, 9.5]), np.array([1.0, 1.0])).tolist()
    [0.9, 0.3]
    """
    s = np.asarray(s_m, dtype=float)
    reach = np.asarray(reach_m, dtype=float)
    return np.minimum(np.minimum(mu_hat_of_s(s), mu_hat_of_s(s + 0.5 * reach)),
                      mu_hat_of_s(s + reach))
