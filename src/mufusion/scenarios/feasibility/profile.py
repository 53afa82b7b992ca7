"""The friction-limited speed profile of a point mass along a line: small pure functions.

A line is a list of :class:`Piece` (straights, clothoids, arcs: curvature linear in the arc
length on each). Along it the point mass may use ``λ μ(s) g`` in any direction (the g-g circle
at the planner's utilisation factor λ): ``v² κ(s) ≤ λ μ(s) g`` and, before a tighter point,
braking with what the lateral demand leaves, ``a_x = √((λμg)² − (v²κ)²)``, at most the brakes'
``a_max``. The backward pass (:func:`backward_profile`) gives ``v_max(s)``, the highest speed at
``s`` from which every later limit can still be met; the forward pass from the entry speed is
cruising at that speed for the brakes' dead time and braking (or holding) after it, so an entry
speed fits if it stays below ``v_max`` over the dead-time travel (:func:`max_entry_speed_mps`).

Friction is a function of the progress along the **lane centre**, as the road stores it; a line
beside the centre (the lane's outer edge) reaches a change point later than the centre by its
longer arcs (:func:`line_position_m` maps centre progress onto the line). The point mass's μ at
``s`` is the lower of the road's under its two axles (``s + l_f`` and ``s − l_r``,
:func:`axle_span_friction`): a drop acts when the front axle reaches it, a rise when the rear axle
has passed it; while the axles straddle a change, cornering in the steady state loads each axle
in proportion to its static load, so the lower μ bounds the lateral acceleration. Derivation:
``docs/feasibility.md``.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np

from mufusion.scenarios.feasibility.common import GRAVITY_MPS2

PROFILE_STEP_M = 0.05
"""Step of the backward pass on curved pieces [m]; each step takes its larger curvature, so the
profile errs on the slow side by O(step) (1 cm/s at 16 m/s on the clothoids tested)."""


class Piece(NamedTuple):
    """A stretch of a line: its length [m], curvature at its start and end [1/m] (linear in
    between) and the lane centre's progress over it [m] (= ``length_m`` on the centre)."""

    length_m: float
    kappa_start_1pm: float
    kappa_end_1pm: float
    centre_length_m: float


FrictionOfS = Callable[[float], float]
LateralCap = Callable[[float, float], float]
"""``(μ, κ) ->`` the highest lateral utilisation the line may use there (≤ 1)."""


def line_position_m(pieces: Sequence[Piece], centre_s_m: float) -> float:
    """Where on the line the lane centre's progress ``centre_s_m`` [m] falls (line progress [m]).

    Linear on each piece; before the first piece and after the last the line runs parallel to
    the centre (a straight).

    Examples
    --------
    >>> outer = [Piece(10.0, 0.0, 0.0, 10.0), Piece(11.0, 0.1, 0.1, 10.0)]
    >>> line_position_m(outer, 15.0), line_position_m(outer, 25.0), line_position_m(outer, -2.0)
    (15.5, 26.0, -2.0)
    """
    if centre_s_m <= 0.0:
        return centre_s_m
    line = centre = 0.0
    for piece in pieces:
        if centre_s_m < centre + piece.centre_length_m:
            return line + (centre_s_m - centre) * piece.length_m / piece.centre_length_m
        line += piece.length_m
        centre += piece.centre_length_m
    return line + centre_s_m - centre


def axle_span_friction(
    mu_before: float, mu_after: float, change_m: float, front_m: float, rear_m: float
) -> tuple[FrictionOfS, tuple[float, ...]]:
    """μ of a point mass whose axles lie ``front_m`` ahead and ``rear_m`` behind it, on a road
    that changes from ``mu_before`` to ``mu_after`` at ``change_m`` (all along one line [m]).

    Returns
    -------
    mu_of, breakpoints
        ``mu_of(s)``: the lower μ under the two axles with the centre of gravity at ``s``;
        ``breakpoints``: where it may jump (``change − front`` and ``change + rear``; none
        when the two μ are equal).

    Examples
    --------
    >>> mu, points = axle_span_friction(0.9, 0.3, 20.0, 1.0, 2.0)  # a drop: the front axle
    >>> [mu(s) for s in (18.9, 19.0, 30.0)], points
    ([0.9, 0.3, 0.3], (19.0, 22.0))
    >>> mu, _ = axle_span_friction(0.3, 0.9, 20.0, 1.0, 2.0)  # a rise: the rear axle
    >>> [mu(s) for s in (19.0, 21.9, 22.0)]
    [0.3, 0.3, 0.9]
    """
    def road(s_m: float) -> float:
        return mu_before if s_m < change_m else mu_after

    def mu_of(s_m: float) -> float:
        return min(road(s_m + front_m), road(s_m - rear_m))

    if mu_before == mu_after:
        return mu_of, ()
    return mu_of, (change_m - front_m, change_m + rear_m)


def lowest_friction(mu_of: FrictionOfS, start_m: float, end_m: float,
                    breakpoints: Sequence[float]) -> float:
    """The lowest ``mu_of`` on ``[start_m, end_m]`` for a piecewise-constant ``mu_of`` that may
    jump only at ``breakpoints`` (each value is held up to the next breakpoint)."""
    inside = [b for b in breakpoints if start_m < b <= end_m]
    return min(mu_of(s) for s in (start_m, end_m, *inside))


def backward_profile(
    pieces: Sequence[Piece], mu_of: FrictionOfS, breakpoints: Sequence[float], lam: float,
    max_decel_mps2: float, lateral_cap: LateralCap | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Backward pass over a line: the nodes s [m], ``v_max²`` and the pointwise limit ``v²``.

    ``lateral_cap(μ, κ)`` bounds the lateral utilisation where it is below λ (the body's
    attitude, :mod:`~mufusion.scenarios.feasibility.attitude`): ``v² κ ≤ min(λ, cap) μ g``;
    braking keeps the whole circle's reach.

    Straights and arcs take one step (exact), clothoids steps of :data:`PROFILE_STEP_M`; every
    step is split at the friction's breakpoints, so μ is constant on each. A node's limit is the
    tighter of its two sides' (a curvature jump counts at once); the pass ends at the line's end
    at that node's limit.

    Raises
    ------
    ValueError
        If ``pieces`` has no piece of positive length.
    """
    steps = _steps(pieces, breakpoints)
    nodes = [steps[0][0]] + [step[1] for step in steps]
    # μ on the step (s_i, s_i+1) is its midpoint's (the breakpoints split the steps).
    mus = [mu_of(0.5 * (step[0] + step[1])) for step in steps]
    accel = [lam * mu * GRAVITY_MPS2 for mu in mus]

    def lim(mu: float, kappa: float) -> float:
        if kappa <= 0.0:
            return math.inf
        share = lam if lateral_cap is None else min(lam, lateral_cap(mu, kappa))
        return share * mu * GRAVITY_MPS2 / kappa

    # A node's limit is the tighter of its two sides, each with its own step's μ and curvature
    # there (a curvature jump counts at once; a change of μ at a jump pairs each μ with its own
    # side's curvature).
    left = [math.inf] + [lim(mu, step[3]) for mu, step in zip(mus, steps, strict=True)]
    right = [lim(mu, step[2]) for mu, step in zip(mus, steps, strict=True)] + [math.inf]
    limit = [min(a, b) for a, b in zip(left, right, strict=True)]
    u = [0.0] * len(nodes)
    u[-1] = limit[-1]
    for i in range(len(nodes) - 2, -1, -1):
        s_a, s_b, k_a, k_b = steps[i]
        step = arc_braking_step if k_a == k_b else braking_step
        u[i] = min(limit[i], step(u[i + 1], accel[i], max(k_a, k_b), s_b - s_a, max_decel_mps2))
    return np.asarray(nodes), np.asarray(u), np.asarray(limit)


def _steps(pieces: Sequence[Piece], breakpoints: Sequence[float]
           ) -> list[tuple[float, float, float, float]]:
    """The pass's steps ``(s_a, s_b, κ_a, κ_b)``, split at every breakpoint inside a step."""
    steps: list[tuple[float, float, float, float]] = []
    start = 0.0
    for piece in pieces:
        length, k0, k1 = piece.length_m, piece.kappa_start_1pm, piece.kappa_end_1pm
        if length <= 0.0:
            continue
        # Straights and arcs in one step (exact, :func:`arc_braking_step`); clothoids in steps.
        n = 1 if k0 == k1 else max(1, math.ceil(length / PROFILE_STEP_M))
        for i in range(n):
            a, b = start + length * i / n, start + length * (i + 1) / n
            ka, kb = k0 + (k1 - k0) * i / n, k0 + (k1 - k0) * (i + 1) / n
            cuts = [a, *sorted(c for c in breakpoints if a < c < b), b]
            for c0, c1 in itertools.pairwise(cuts):
                steps.append((c0, c1, ka + (kb - ka) * (c0 - a) / (b - a),
                              ka + (kb - ka) * (c1 - a) / (b - a)))
        start += length
    if not steps:
        raise ValueError("a line needs at least one piece of positive length")
    return steps


def braking_step(u_end: float, a_total: float, kappa: float, ds: float,
                 max_decel_mps2: float) -> float:
    """v² at a step's start from ``u_end`` = v² at its end, braking with what the lateral demand
    at the start (the faster end) leaves: ``w = u_end + 2 ds √(a² − (w κ)²)``.

    Implicit in ``w``: the explicit form (the lateral demand at the slower end) is not monotone
    in ``u_end`` near the limit, so more friction further on could lower v_max by ~1e-5 m/s;
    this one is (``w`` rises with ``u_end``) and errs slow.

    Examples
    --------
    >>> braking_step(100.0, 5.0, 0.0, 10.0, 1e9)  # a straight: v² + 2 a ds
    200.0
    """
    if kappa <= 0.0:
        return arc_braking_step(u_end, a_total, kappa, ds, max_decel_mps2)
    if u_end * kappa >= a_total:
        return u_end  # no braking left at the end's lateral demand
    # (w − u)² = 4 ds² (a² − w² κ²), root w ≥ u.
    c = (2.0 * ds * kappa) ** 2
    disc = 4.0 * ds * ds * (a_total * a_total * (1.0 + c) - (kappa * u_end) ** 2)
    w = (u_end + math.sqrt(disc)) / (1.0 + c)
    return min(w, u_end + 2.0 * max_decel_mps2 * ds)


def arc_braking_step(u_end: float, a_total: float, kappa: float, ds: float,
                     max_decel_mps2: float) -> float:
    """v² at the start of ``ds`` of constant curvature ``kappa`` from ``u_end`` at its end, braking
    with all the g-g circle leaves: exact.

    With ``w = κ v²`` (the lateral acceleration) braking backwards gives
    ``dw/ds = 2κ √(a² − w²)``, so ``asin(w/a)`` grows by ``2κ ds`` (at most to π/2, the arc's
    limit); where the circle would leave more than the brakes' ``a_max``, w grows linearly by
    ``2κ a_max ds`` first, up to ``√(a² − a_max²)``. On a straight (κ = 0):
    ``u + 2 min(a, a_max) ds``.

    Examples
    --------
    >>> round(arc_braking_step(50.0, 4.0, 0.04, 10.0, 1e9), 4)  # 100 sin(asin(0.5) + 0.8)
    96.9602
    """
    if kappa <= 0.0:
        return u_end + 2.0 * min(a_total, max_decel_mps2) * ds
    w = kappa * u_end
    if w >= a_total:
        return u_end  # at or above the limit: nothing left to brake with
    if max_decel_mps2 < a_total:  # the brakes bind while the lateral demand is low
        w_switch = math.sqrt(a_total * a_total - max_decel_mps2 * max_decel_mps2)
        if w < w_switch:
            linear = 2.0 * kappa * max_decel_mps2 * ds
            if w + linear <= w_switch:
                return (w + linear) / kappa
            ds -= (w_switch - w) / (2.0 * kappa * max_decel_mps2)
            w = w_switch
    angle = min(math.asin(w / a_total) + 2.0 * kappa * ds, 0.5 * math.pi)
    return a_total * math.sin(angle) / kappa


def max_entry_speed_mps(s_m: np.ndarray, reach_v2: np.ndarray, dead_time_s: float,
                        upper_mps: float) -> float:
    """Highest entry speed ``v`` that cruises through the dead time within the profile:
    ``v² ≤ reach(v τ)`` with ``reach`` the running minimum of ``v_max²`` from the start.

    Bisection on a monotone predicate (``reach`` falls with s, ``v²`` rises with v) in
    ``[0, upper_mps]``.
    """
    def cruise_ok(v: float) -> bool:
        return v * v <= float(np.interp(v * dead_time_s, s_m, reach_v2))

    lo, hi = 0.0, upper_mps
    for _ in range(60):  # 1e-18 of the bracket
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if cruise_ok(mid) else (lo, mid)
    return lo
