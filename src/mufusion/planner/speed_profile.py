"""Curvature- and friction-aware speed reference: the point mass's highest speed along the road.

A cost that tracks a constant cruise speed pulls every plan to the friction limit wherever the
road curves, and only as far as the horizon reaches: the plans brake as late as the model allows,
enter the curve at its limit and end the horizon accelerating inside it. Any mismatch between the
plan and the vehicle then leaves no room but the lane's. Tracking instead the highest speed a point
mass could hold along the lane centre with the friction the planner may use (``v² |κ| ≤ a`` and,
before a tighter point, braking with ``√(a² − (v²κ)²)``; ``a = λ cos(π/n) μ̂ g``, what an n-sided
polygon of radius ``λ μ̂ F_z`` grants in pure braking or cornering) asks for a speed the plan can
keep, sees curves beyond the time horizon (the profile reaches a stopping distance further), and
leaves the lane's play as a margin. The braking ramps may use only a share of that deceleration
(``braking_fraction``; the planner's default 0.8), so braking a plan loses before a curve can be
made up instead of arriving as excess speed. A forward pass from the vehicle's own speed
(:func:`regain_limited_profile_mps`) lets the reference rise only as fast as the drive's cap on
the g-g ellipse allows, so a vehicle below it inside a curve is not asked to regain speed at once,
and not at all on its way to a curve that it must slow down for.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from types import ModuleType

import numpy as np

from mufusion.planner.axle_reach import PitchTransfer, two_axle_braking_mps2
from mufusion.planner.unseen_road import MuOfS
from mufusion.vehicle.params import GRAVITY_MPS2

_COMPILED: ModuleType | None
try:  # the passes compiled (bit for bit the loops below), where the install built them
    import mufusion.planner._speed_profile_c as _COMPILED
except ImportError:  # pragma: no cover - a tree without the compiled modules
    _COMPILED = None

PROFILE_STEP_M = 1.0
"""Grid step of the profile [m]; each step brakes with its larger curvature (errs slow)."""
MAX_LOOKAHEAD_M = 300.0
"""Longest stretch of road the profile looks at [m]."""


def max_speed_profile_mps(
    s_m: np.ndarray,
    curvature_1pm: np.ndarray,
    mu: np.ndarray,
    accel_fraction: float,
    end_speed_mps: float,
    braking_fraction: float = 1.0,
    transfer: PitchTransfer | None = None,
) -> np.ndarray:
    """Highest speed at each grid point from which every later curvature limit can be met.

    Parameters
    ----------
    s_m
        Increasing progress grid [m], shape (M,).
    curvature_1pm, mu
        Road curvature [1/m] and friction [-] at the grid points, shape (M,).
    accel_fraction
        Fraction of ``μ g`` the point mass may use, in (0, 1].
    end_speed_mps
        Speed allowed beyond the last grid point [m/s] (e.g. the cruise speed).
    braking_fraction
        Share of the friction left after the curvature's lateral demand that the braking ramps
        before a tighter point use, in (0, 1]. 1 brakes as late as the friction allows; less
        starts braking earlier and keeps the rest as a reserve (the curvature limits
        themselves are unchanged).
    transfer
        The vehicle's pitch load transfer: the ramps brake with what its two axles reach beside
        the lateral demand (:func:`~mufusion.planner.axle_reach.two_axle_braking_mps2`) instead
        of the point mass's ``√(a² − a_y²)``.

    Returns
    -------
    ndarray
        Shape (M,) [m/s], never above ``end_speed_mps``.

    Raises
    ------
    ValueError
        If the arrays differ in shape, ``s_m`` does not increase, or ``accel_fraction`` or
        ``braking_fraction`` is not in (0, 1].

    Examples
    --------
    >>> s = np.arange(0.0, 31.0)
    >>> k = np.where(s >= 20.0, 1.0 / 28.0, 0.0)
    >>> v = max_speed_profile_mps(s, k, np.full(s.size, 0.4), 0.9, 20.0)
    >>> # √(3.5316·28); the step into the arc brakes with its curvature: √(98.8848 + 2·3.5316·19)
    >>> round(float(v[-1]), 3), round(float(v[0]), 3)
    (9.944, 15.267)
    """
    s = np.asarray(s_m, dtype=float)
    kappa = np.abs(np.asarray(curvature_1pm, dtype=float))
    mu_arr = np.asarray(mu, dtype=float)
    if not (s.shape == kappa.shape == mu_arr.shape and s.ndim == 1 and s.size >= 1):
        raise ValueError("s_m, curvature_1pm and mu must be 1-D arrays of equal length")
    if np.any(np.diff(s) <= 0.0):
        raise ValueError("s_m must increase")
    if not 0.0 < accel_fraction <= 1.0:
        raise ValueError(f"accel_fraction must be in (0, 1], got {accel_fraction!r}")
    if not 0.0 < braking_fraction <= 1.0:
        raise ValueError(f"braking_fraction must be in (0, 1], got {braking_fraction!r}")
    accel = accel_fraction * mu_arr * GRAVITY_MPS2
    with np.errstate(divide="ignore"):
        limit = np.where(kappa > 0.0, accel / np.maximum(kappa, 1e-300), np.inf)
    # The backward pass is sequential: compiled where built, else on Python floats (~4x faster
    # than on numpy scalars); either way the same IEEE operations in the same order and
    # ``min``/``max``'s argument semantics (identical results, NaN included).
    u_arr = np.minimum(limit, end_speed_mps**2)
    if _COMPILED is not None:
        _COMPILED.backward_pass(u_arr, kappa, accel, np.ascontiguousarray(s),
                                2.0 * braking_fraction, *_transfer_args(transfer))
        return np.sqrt(u_arr)
    u = u_arr.tolist()
    k_list, a_list, s_list = kappa.tolist(), accel.tolist(), s.tolist()
    u_next, k_next, s_next = u[-1], k_list[-1], s_list[-1]
    two_b = 2.0 * braking_fraction
    for i in range(s.size - 2, -1, -1):
        k_i, s_i, a = k_list[i], s_list[i], a_list[i]
        lateral = u_next * (k_next if k_next > k_i else k_i)  # max(k_i, k_next)
        braking = (math.sqrt(max(a * a - lateral * lateral, 0.0)) if transfer is None
                   else two_axle_braking_mps2(a, lateral, transfer))
        reachable = u_next + two_b * braking * (s_next - s_i)
        u_next = u[i] = reachable if reachable < u[i] else u[i]  # min(u[i], reachable)
        k_next, s_next = k_i, s_i
    return np.sqrt(np.array(u))


def _transfer_args(transfer: PitchTransfer | None) -> tuple[float, float, float]:
    """The compiled passes' ``p, hl, g`` (``hl < 0``: the point mass's reach)."""
    if transfer is None:
        return 0.0, -1.0, GRAVITY_MPS2
    return transfer.front_share, transfer.height_per_wheelbase, GRAVITY_MPS2


def _pass_arrays(
    s_m: np.ndarray, curvature_1pm: np.ndarray, mu: np.ndarray, accel_fraction: float,
    profile_mps: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The forward passes' inputs: the grid (contiguous), ``|κ|``, the friction's acceleration
    ``accel_fraction · μ g`` and the profile's squared speeds."""
    return (np.ascontiguousarray(s_m, dtype=float), np.abs(np.asarray(curvature_1pm, dtype=float)),
            accel_fraction * np.asarray(mu, dtype=float) * GRAVITY_MPS2,
            np.asarray(profile_mps, dtype=float) ** 2)


def regain_limited_profile_mps(
    s_m: np.ndarray,
    curvature_1pm: np.ndarray,
    mu: np.ndarray,
    accel_fraction: float,
    profile_mps: np.ndarray,
    start_speed_mps: float,
    max_accel_mps2: float,
    share: float = 1.0,
) -> np.ndarray:
    """``profile_mps`` capped by how fast a point mass from ``start_speed_mps`` regains speed.

    The forward pass of a speed profile: from the start, each grid step may add speed with
    ``a_x ≤ max_accel_mps2 · √(1 − (v² |κ| / (b a))²)``, ``a = accel_fraction · μ g``,
    ``b = share``, the g-g ellipse whose semi-axes are the drive's acceleration cap and the share
    ``b`` of the lateral friction (on a straight the whole cap, cornering at ``b a`` or beyond
    nothing). A vehicle below the profile inside a curve is then asked to regain speed only as
    fast as its cornering leaves friction for it, instead of at once; with ``b < 1`` the
    reference asks for no drive at all while the plans corner beyond the share the braking ramps
    use, which keeps the driven axle's reserve for the plans' lateral corrections
    (docs/decisions/0119). Where the profile somewhere ahead lies below the start speed, no
    speed is added before its (first) lowest point: a vehicle that is below the braking ramp
    towards a curve, e.g. after a friction probe or a rise of μ̂, holds its speed until the ramp
    meets it instead of speeding up to brake harder later.

    Parameters
    ----------
    s_m, curvature_1pm, mu, accel_fraction
        As for :func:`max_speed_profile_mps` (same grid).
    profile_mps
        The backward pass's speeds on the grid, shape (M,) [m/s].
    start_speed_mps
        Speed at the first grid point [m/s], ≥ 0.
    max_accel_mps2
        The drive's acceleration cap [m/s²], > 0.
    share
        Share ``b`` of the friction's lateral reach the regain's ellipse spans, in (0, 1].

    Returns
    -------
    ndarray
        Shape (M,) [m/s], never above ``profile_mps``.

    Examples
    --------
    >>> s = np.arange(0.0, 3.0)
    >>> v = regain_limited_profile_mps(s, np.zeros(3), np.full(3, 0.8), 0.9, np.full(3, 20.0),
    ...                                10.0, 1.5)
    >>> [round(float(x), 4) for x in v]  # √(100 + 2·1.5·1), √(103 + 3)
    [10.0, 10.1489, 10.2956]
    >>> ramp = np.array([20.0, 12.0, 8.0, 20.0])  # a curve at 8 m/s two metres ahead
    >>> v = regain_limited_profile_mps(np.arange(4.0), np.zeros(4), np.full(4, 0.8), 0.9, ramp,
    ...                                10.0, 1.5)
    >>> [round(float(x), 4) for x in v]  # held, the ramp, its bottom, then √(64 + 3)
    [10.0, 10.0, 8.0, 8.1854]
    """
    if not start_speed_mps >= 0.0 or not max_accel_mps2 > 0.0:
        raise ValueError("start_speed_mps must be >= 0 and max_accel_mps2 > 0, got "
                         f"{start_speed_mps!r} and {max_accel_mps2!r}")
    if not 0.0 < share <= 1.0:
        raise ValueError(f"share must be in (0, 1], got {share!r}")
    s_arr, kappa_arr, accel_arr, cap_arr = _pass_arrays(s_m, curvature_1pm, mu,
                                                        share * accel_fraction, profile_mps)
    cap = cap_arr.tolist()
    w = min(start_speed_mps * start_speed_mps, cap[0])
    # Where the profile ahead falls below the vehicle's speed, the way to its lowest point is a
    # deceleration: speed regained on it would only have to be braked away again, later and
    # closer to the curve (docs/decisions/0044, "No speed regained on the way to a curve").
    lowest = min(cap)
    bottom = cap.index(lowest) if lowest < w else 0
    # The compiled pass where the friction is positive (or NaN): the loop below divides by it
    # and raises on zero, and takes a square root that is undefined for a negative one.
    if _COMPILED is not None and not np.any(accel_arr <= 0.0):
        out_arr = np.empty(cap_arr.size)
        _COMPILED.forward_pass(out_arr, cap_arr, kappa_arr, accel_arr, s_arr, w, bottom,
                               float(max_accel_mps2))
        return np.sqrt(out_arr)
    kappa, accel, s_list = kappa_arr.tolist(), accel_arr.tolist(), s_arr.tolist()
    out = [w]
    for i in range(len(cap) - 1):
        if i < bottom:
            w = min(cap[i + 1], w)
        else:
            lateral = w * max(kappa[i], kappa[i + 1])
            ratio = min(lateral / accel[i], 1.0)
            w = min(cap[i + 1], w + 2.0 * max_accel_mps2 * math.sqrt(1.0 - ratio * ratio)
                    * (s_list[i + 1] - s_list[i]))
        out.append(w)
    return np.sqrt(np.array(out))


def descent_limited_profile_mps(
    s_m: np.ndarray,
    curvature_1pm: np.ndarray,
    mu: np.ndarray,
    accel_fraction: float,
    profile_mps: np.ndarray,
    start_speed_mps: float,
    braking_fraction: float,
    transfer: PitchTransfer | None = None,
) -> np.ndarray:
    """``profile_mps`` raised to where a point mass from ``start_speed_mps`` could brake to.

    From the start, each grid step may lose speed with ``a_x ≤ √((b a)² − (v² |κ|)²)``,
    ``a = accel_fraction · μ g``, ``b = braking_fraction``: what the cornering leaves of the
    share ``b`` of the friction, so braking and cornering together never use more than that
    share (a vehicle cornering beyond it is asked for no braking at all). A profile that falls
    below the vehicle's speed faster than that is raised to the ramp: the reference then asks
    for braking within the share, never for a step.

    Parameters
    ----------
    s_m, curvature_1pm, mu, accel_fraction, braking_fraction, transfer
        As for :func:`max_speed_profile_mps` (same grid; ``transfer``: the two axles' reach on
        the share ``b`` of the friction).
    profile_mps
        The speeds to raise, shape (M,) [m/s].
    start_speed_mps
        Speed at the first grid point [m/s], ≥ 0.

    Returns
    -------
    ndarray
        Shape (M,) [m/s], never below ``profile_mps``.

    Examples
    --------
    >>> s = np.arange(0.0, 4.0)
    >>> v = descent_limited_profile_mps(s, np.zeros(4), np.full(4, 0.5), 1.0, np.full(4, 5.0),
    ...                                 10.0, 1.0)
    >>> [round(float(x), 3) for x in v]  # √(100 − 2·0.5·9.81·k)
    [10.0, 9.497, 8.965, 8.401]
    """
    if not start_speed_mps >= 0.0:
        raise ValueError(f"start_speed_mps must be >= 0, got {start_speed_mps!r}")
    s_arr, kappa_arr, accel_arr, floor_arr = _pass_arrays(s_m, curvature_1pm, mu,
                                                          accel_fraction, profile_mps)
    if _COMPILED is not None:
        out_arr = np.empty(floor_arr.size)
        _COMPILED.descent_pass(out_arr, floor_arr, kappa_arr, accel_arr, s_arr,
                               start_speed_mps * start_speed_mps, float(braking_fraction),
                               *_transfer_args(transfer))
        return np.sqrt(out_arr)
    kappa, accel = kappa_arr.tolist(), accel_arr.tolist()
    s_list, floor = s_arr.tolist(), floor_arr.tolist()
    w = max(start_speed_mps * start_speed_mps, floor[0])
    out = [w]
    for i in range(len(floor) - 1):
        lateral = w * max(kappa[i], kappa[i + 1])
        share = braking_fraction * accel[i]
        braking = (math.sqrt(max(share * share - lateral * lateral, 0.0)) if transfer is None
                   else two_axle_braking_mps2(share, lateral, transfer))
        w = max(w - 2.0 * braking * (s_list[i + 1] - s_list[i]), floor[i + 1])
        out.append(w)
    return np.sqrt(np.array(out))


def curve_speed_reference_mps(
    stage_s_m: np.ndarray,
    curvature_of_s: Callable[[np.ndarray], np.ndarray],
    mu_hat_of_s: Callable[[np.ndarray], np.ndarray],
    cruise_speed_mps: float,
    accel_fraction: float,
    horizon_time_s: float,
    braking_fraction: float = 1.0,
    regain: tuple[float, float, float] | None = None,
    unseen: tuple[MuOfS, float] | None = None,
    transfer: PitchTransfer | None = None,
) -> np.ndarray:
    """The cruise speed capped by :func:`max_speed_profile_mps` at the stages' positions.

    The profile runs from the first stage over the horizon's reach at the cruise speed plus the
    stopping distance from it at the lowest μ̂ ahead (at most :data:`MAX_LOOKAHEAD_M`), so a
    curve beyond the horizon already lowers the reference of its last stages. ``regain``
    ``(start_speed_mps, max_accel_mps2, share)`` caps it by :func:`regain_limited_profile_mps`
    from the vehicle's speed at the first stage. ``unseen`` ``(mu_of_s, start_speed_mps)``, the
    friction with the road beyond the estimate at its floor (:meth:`UnseenRoad.cap`), caps it
    also by that friction's profile, lowered from the vehicle's speed no faster than
    :func:`descent_limited_profile_mps` brakes within ``braking_fraction`` of the friction,
    cornering included: a hypothesis about the road not yet seen asks for the braking the
    reference's straight ramps ask for anyway, never for a step down, and never for braking
    that leaves a plan cornering near its limit no friction for its lateral corrections
    (docs/decisions/0084). ``transfer``: every braking ramp with the two axles' reach
    (docs/decisions/0106).
    """
    s0 = float(stage_s_m[0])
    coarse = s0 + np.arange(0.0, MAX_LOOKAHEAD_M + PROFILE_STEP_M, PROFILE_STEP_M)
    mu_min = max(float(np.min((mu_hat_of_s if unseen is None else unseen[0])(coarse))), 0.05)
    reach = cruise_speed_mps * horizon_time_s + cruise_speed_mps**2 / (
        2.0 * braking_fraction * accel_fraction * mu_min * GRAVITY_MPS2)
    grid = coarse[coarse <= s0 + min(reach, MAX_LOOKAHEAD_M) + PROFILE_STEP_M]
    kappa = np.asarray(curvature_of_s(grid), dtype=float) * np.ones_like(grid)

    def profile_on(mu_of_s: MuOfS) -> tuple[np.ndarray, np.ndarray]:
        # np.clip's values for these non-zero bounds, without its per-call overhead.
        mu = np.minimum(np.maximum(np.asarray(mu_of_s(grid), dtype=float), 0.05), 2.0)
        return mu, max_speed_profile_mps(grid, kappa, mu, accel_fraction, cruise_speed_mps,
                                         braking_fraction, transfer)

    mu, profile = profile_on(mu_hat_of_s)
    if regain is not None:
        profile = regain_limited_profile_mps(grid, kappa, mu, accel_fraction, profile, *regain)
    if unseen is not None:
        # After the regain pass: the floor's curve is always ahead, and as the lowest point of
        # the profile it would hold a vehicle below it at its speed for good (0044's rule is for
        # curves that exist).
        floor_mu, floor = profile_on(unseen[0])
        profile = np.minimum(profile, descent_limited_profile_mps(
            grid, kappa, floor_mu, accel_fraction, floor, unseen[1], braking_fraction, transfer))
    return np.interp(np.asarray(stage_s_m, dtype=float), grid, profile)
