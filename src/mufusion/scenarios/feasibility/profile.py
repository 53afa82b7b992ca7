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
        ``breakpoints``: where it may jump (``change − front`` and ``change + rear``).

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

    return mu_of, (change_m - front_m, change_m + rear_m)


def lowest_friction(mu_of: FrictionOfS, start_m: float, end_m: float,
                    breakpoints: Sequence[float]) -> float:
    """The lowest ``mu_of`` on ``[start_m, end_m]`` for a piecewise-constant ``mu_of`` that may
    jump only at ``breakpoints`` (each value is held up to the next breakpoint)."""
    inside = [b for b in breakpoints if start_m < b <= end_m]
    return min(mu_of(s) for s in (start_m, end_m, *inside))


def backward_profile(
    pieces: Sequence[Piece], mu_of: FrictionOfS, breakpoints: Sequence[float], lam: float,
    max_decel_mps2: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Backward pass over a line: the nodes s [m], ``v_max²`` and the pointwise limit ``v²``.

    Straights take one step (exact), curved pieces steps of :data:`PROFILE_STEP_M`; every step
    is split at the friction's breakpoints, so μ is constant on each. A node's curvature is the
    larger of its two steps' ends (a curvature jump counts at once) and its μ the lower of its two
    steps'; the pass ends at the line's end at that node's limit.

    Raises
    ------
    ValueError
        If ``pieces`` has no piece of positive length.
    """
    steps = _steps(pieces, breakpoints)
    nodes = [steps[0][0]] + [step[1] for step in steps]
    step_k = [max(step[2], step[3]) for step in steps]
    ends = [steps[0][2], *[step[3] for step in steps]]
    starts = [*[step[2] for step in steps], steps[-1][3]]
    curv = [max(a, b) for a, b in zip(ends, starts, strict=True)]
    # μ on the step (s_i, s_i+1) is its midpoint's; a node takes the lower of its two steps.
    mu_step = [mu_of(0.5 * (step[0] + step[1])) for step in steps]
    mu_node = [min(a, b) for a, b in zip([mu_step[0], *mu_step], [*mu_step, mu_step[-1]],
                                         strict=True)]
    limit = [lam * m * GRAVITY_MPS2 / k if k > 0.0 else math.inf
             for m, k in zip(mu_node, curv, strict=True)]
    u = [0.0] * len(nodes)
    u[-1] = limit[-1]
    for i in range(len(nodes) - 2, -1, -1):
        a_total = lam * mu_step[i] * GRAVITY_MPS2
        u[i] = min(limit[i], braking_step(u[i + 1], a_total, step_k[i],
                                          nodes[i + 1] - nodes[i], max_decel_mps2))
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
        n = 1 if k0 == k1 == 0.0 else max(1, math.ceil(length / PROFILE_STEP_M))
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
        return u_end + 2.0 * min(a_total, max_decel_mps2) * ds
    if u_end * kappa >= a_total:
        return u_end  # no braking left at the end's lateral demand
    # (w − u)² = 4 ds² (a² − w² κ²), root w ≥ u.
    c = (2.0 * ds * kappa) ** 2
    disc = 4.0 * ds * ds * (a_total * a_total * (1.0 + c) - (kappa * u_end) ** 2)
    w = (u_end + math.sqrt(disc)) / (1.0 + c)
    return min(w, u_end + 2.0 * max_decel_mps2 * ds)


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
