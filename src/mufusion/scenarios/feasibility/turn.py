"""Turn feasibility: can a point mass on the true μ slow to the curve's limit speed in time?

The curve (a straight, an entry clothoid, a circular arc of radius R, an exit clothoid, together
turning by θ) is followed along the lane centre (*centreline*) or, using the lane's play, along
the better of two lines: the outer edge of the lane (*outer*, radius ``R + p_out`` from the same
turn-in point) and the widest circle through the curve (*cut*, radius R' from the outer edge to
the inner edge at the apex and back, which turns in earlier). Along a line the point mass may use
the acceleration ``λ μ(s) g`` in any direction (λ: the planner's utilisation factor), so its
speed is bounded by ``v² κ(s) ≤ λ μ(s) g`` and, before a tighter point, by braking with what the
lateral demand leaves: ``a_x = √((λμg)² − (v²κ)²)``.
A backward pass from the curve's end gives the highest speed ``v_max(s)`` from which every later
limit can still be met (each step braking with what the lateral demand at its faster end
leaves); a first-order actuator lag τ is a dead time τ at the entry speed before braking starts
(its exact response brakes ``a τ²/2`` more: the dead time is conservative).
Derivation and figures: ``docs/feasibility.md``.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.special import fresnel

from mufusion.scenarios.feasibility.common import (
    GRAVITY_MPS2,
    FeasibilityClass,
    classify_speed_margin,
    require_fraction,
    require_positive,
)

# Step of the backward pass on curved pieces [m]; it takes the larger curvature of each step, so
# the profile errs on the slow side by O(step) (1 cm/s at 16 m/s on the clothoids tested).
PROFILE_STEP_M = 0.05


@dataclass(frozen=True)
class TurnLimit:
    """The turn along one line (centreline, outer edge or cut within the play).

    Attributes
    ----------
    path
        ``"centreline"``: the lane centre; ``"outer"``: the lane's outer edge (the footprint
        touching it); ``"cut"``: the widest circle inside the lane's play.
    radius_m
        Smallest radius of the path [m] (R, or the effective radius R' with play).
    limit_speed_mps
        ``√(λ μ g R)`` at the tightest point, with that point's μ [m/s].
    limit_distance_m
        Distance from the vehicle's start to where that limit first applies [m]: the arc's start
        (the end of the entry clothoid) for the centreline and the outer line, the circle's start
        for the cut.
    max_entry_speed_mps
        Highest entry speed from which the limit is met, dead time included [m/s].
    braking_distance_m
        Distance before the limit point at which braking must be commanded, 0 if the entry speed
        never exceeds the limits [m].
    spare_distance_m
        How much later than the start braking could still be commanded [m] (negative: too late).
    margin_mps
        ``max_entry_speed_mps`` − entry speed [m/s].
    feasibility_class
        From the margin and the marginal band.
    """

    path: Literal["centreline", "outer", "cut"]
    radius_m: float
    limit_speed_mps: float
    limit_distance_m: float
    max_entry_speed_mps: float
    braking_distance_m: float
    spare_distance_m: float
    margin_mps: float
    feasibility_class: FeasibilityClass


@dataclass(frozen=True)
class TurnFeasibility:
    """Verdict on a turn variant.

    ``centreline`` follows the lane centre; ``with_play`` is the best of the centreline, the outer
    line and the cut circle (all fit in the lane). ``feasibility_class`` is *feasible* when the
    centreline is feasible (the vehicle need not use the play), *infeasible* when even
    ``with_play`` is, *marginal* otherwise; ``margin_mps`` is the centreline's margin.
    """

    feasibility_class: FeasibilityClass
    margin_mps: float
    entry_speed_mps: float
    centreline: TurnLimit
    with_play: TurnLimit
    play_inner_m: float
    play_outer_m: float
    clothoid_shift_m: float
    dead_time_s: float
    utilization_factor: float


def clothoid_offsets_m(radius_m: float, clothoid_m: float) -> tuple[float, float]:
    """Shift and tangent offset of an arc entered through a clothoid (exact, Fresnel integrals).

    A clothoid of length L from curvature 0 to 1/R moves the arc's centre away from the entry
    tangent to ``R + shift`` (``shift ≈ L²/(24R)``) and ``x_M ≈ L/2`` along it from the clothoid's
    start.

    Returns
    -------
    shift_m, tangent_offset_m

    Examples
    --------
    >>> [round(v, 4) for v in clothoid_offsets_m(28.0, 5.0)]  # L²/(24R) = 0.0372, L/2 = 2.5
    [0.0372, 2.4993]
    """
    if clothoid_m == 0.0:
        return 0.0, 0.0
    scale = math.sqrt(math.pi * radius_m * clothoid_m)  # A√π with A² = R L
    s_int, c_int = fresnel(clothoid_m / scale)
    x_end, y_end = scale * float(c_int), scale * float(s_int)
    tau = clothoid_m / (2.0 * radius_m)  # heading at the clothoid's end
    return y_end + radius_m * math.cos(tau) - radius_m, x_end - radius_m * math.sin(tau)


def effective_radius_m(
    radius_m: float, turn_angle_rad: float, play_inner_m: float, play_outer_m: float,
    shift_m: float = 0.0,
) -> float:
    """Radius of the widest circle through a curve of angle θ inside the lane's play.

    The circle touches the outer edge on both straights and the inner edge at the curve's apex:
    ``R' = R − p_in + (p_in + p_out + shift) / (1 − cos(θ/2))``.

    Examples
    --------
    >>> round(effective_radius_m(28.0, math.pi / 2, 0.45, 0.45), 3)  # 28 + 0.45 (2/0.2929 − 1)
    30.623
    """
    return radius_m - play_inner_m + (play_inner_m + play_outer_m + shift_m) / (
        1.0 - math.cos(0.5 * turn_angle_rad)
    )


def _profile(
    pieces: list[tuple[float, float, float]], mu_of: Callable[[float], float], lam: float,
    max_decel_mps2: float, change_m: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Backward pass over ``pieces`` (length, κ_start, κ_end): grid s, v_max², limit v² per node."""
    steps: list[tuple[float, float, float, float]] = []  # (s_a, s_b, κ_a, κ_b)
    start = 0.0
    for length, k0, k1 in pieces:
        n = 1 if k0 == k1 == 0.0 else max(1, math.ceil(length / PROFILE_STEP_M))
        for i in range(n):
            a, b = start + length * i / n, start + length * (i + 1) / n
            ka, kb = k0 + (k1 - k0) * i / n, k0 + (k1 - k0) * (i + 1) / n
            if a < change_m < b:  # split the step at the friction change
                kc = ka + (kb - ka) * (change_m - a) / (b - a)
                steps += [(a, change_m, ka, kc), (change_m, b, kc, kb)]
            else:
                steps.append((a, b, ka, kb))
        start += length
    nodes = [steps[0][0]] + [step[1] for step in steps]
    step_k = [max(step[2], step[3]) for step in steps]
    # A node's curvature is the larger of its two steps' ends (a curvature jump counts at once).
    ends = [steps[0][2], *[step[3] for step in steps]]
    starts = [*[step[2] for step in steps], steps[-1][3]]
    curv = [max(a, b) for a, b in zip(ends, starts, strict=True)]
    s = np.asarray(nodes)
    # μ on the step (s_i, s_i+1) is its midpoint's; a node takes the lower of its two steps.
    mu_step = [mu_of(0.5 * (a + b)) for a, b in itertools.pairwise(nodes)]
    mu_node = [min(a, b) for a, b in zip([mu_step[0], *mu_step], [*mu_step, mu_step[-1]],
                                         strict=True)]
    limit = [lam * m * GRAVITY_MPS2 / k if k > 0.0 else math.inf
             for m, k in zip(mu_node, curv, strict=True)]
    u = [0.0] * len(nodes)
    u[-1] = limit[-1]
    for i in range(len(nodes) - 2, -1, -1):
        a_total = lam * mu_step[i] * GRAVITY_MPS2
        u[i] = min(limit[i], _braking_step(u[i + 1], a_total, step_k[i],
                                           nodes[i + 1] - nodes[i], max_decel_mps2))
    return s, np.asarray(u), np.asarray(limit)


def _braking_step(u_end: float, a_total: float, kappa: float, ds: float,
                  max_decel_mps2: float) -> float:
    """v² at a step's start from ``u_end`` = v² at its end, braking with what the lateral demand
    at the start (the faster end) leaves: ``w = u_end + 2 ds √(a² − (w κ)²)``.

    Implicit in ``w``: the explicit form (the lateral demand at the slower end) is not monotone
    in ``u_end`` near the limit, so more friction further on could lower v_max by ~1e-5 m/s;
    this one is (``w`` rises with ``u_end``) and errs slow.
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


def _assess(
    path: Literal["centreline", "outer", "cut"], radius_m: float,
    pieces: list[tuple[float, float, float]], mu_of: Callable[[float], float], change_m: float,
    entry_speed_mps: float, lam: float, dead_time_s: float, max_decel_mps2: float,
) -> TurnLimit:
    s, u, limit = _profile(pieces, mu_of, lam, max_decel_mps2, change_m)
    reach = np.minimum.accumulate(u)  # v² allowed for cruising from the start up to s

    def cruise_ok(v: float) -> bool:
        return v * v <= float(np.interp(v * dead_time_s, s, reach))

    lo, hi = 0.0, math.sqrt(u[0])
    for _ in range(60):  # bisection on a monotone predicate: 1e-18 of the bracket
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if cruise_ok(mid) else (lo, mid)
    v_max = lo
    tight = int(np.argmin(limit))
    v0 = entry_speed_mps
    d_t = v0 * dead_time_s
    if v0 * v0 <= reach[-1]:
        braking, spare = 0.0, float(s[tight])
    else:
        # Last point up to which cruising at v0 is still allowed (the braking point).
        above = np.nonzero(reach >= v0 * v0)[0]
        if above.size:
            j = int(above[-1])
            s_b = float(s[j] + (s[j + 1] - s[j]) * (reach[j] - v0 * v0)
                        / max(reach[j] - reach[j + 1], 1e-12))
        else:  # too fast already at the start: extrapolate the first step's braking
            a0 = min(lam * mu_of(0.0) * GRAVITY_MPS2, max_decel_mps2)
            s_b = -(v0 * v0 - u[0]) / (2.0 * a0)
        braking, spare = float(s[tight]) - float(s_b) + d_t, float(s_b) - d_t
    margin = v_max - v0
    return TurnLimit(
        path=path, radius_m=radius_m, limit_speed_mps=math.sqrt(limit[tight]),
        limit_distance_m=float(s[tight]), max_entry_speed_mps=v_max,
        braking_distance_m=braking, spare_distance_m=spare, margin_mps=margin,
        feasibility_class=classify_speed_margin(margin, v0),
    )


def turn_feasibility(
    *,
    entry_speed_mps: float,
    radius_m: float,
    turn_angle_rad: float,
    turn_start_ahead_m: float,
    clothoid_m: float,
    mu_before: float,
    mu_turn: float,
    friction_change_ahead_m: float,
    utilization_factor: float,
    dead_time_s: float,
    lane_width_m: float,
    vehicle_width_m: float,
    vehicle_length_m: float,
    max_decel_mps2: float = math.inf,
) -> TurnFeasibility:
    """Whether a point mass can slow from ``entry_speed_mps`` to the curve's limit in time.

    Parameters
    ----------
    entry_speed_mps
        Speed at the start [m/s], > 0.
    radius_m, turn_angle_rad
        Arc radius [m] and the whole curve's turn angle (clothoids included) [rad], in (0, π].
    turn_start_ahead_m
        Distance from the vehicle's centre of gravity to the start of the curve (its entry
        clothoid) [m], ≥ 0.
    clothoid_m
        Length of each clothoid [m], ≥ 0; the arc turns by ``θ − clothoid_m / radius_m``.
    mu_before, mu_turn, friction_change_ahead_m
        True friction before and after the change point, which lies ``friction_change_ahead_m``
        [m] ahead of the start (negative: behind it).
    utilization_factor
        λ in (0, 1]: the fraction of μ g the planner may use.
    dead_time_s
        Actuator dead time before braking acts [s], ≥ 0 (a first-order lag's time constant).
    lane_width_m, vehicle_width_m, vehicle_length_m
        Lane and footprint size [m]; the play per side is ``(lane − width)/2``, on the outer side
        less the footprint's bulge ``length²/(8R)`` in the curve.
    max_decel_mps2
        Deceleration the brakes can give [m/s²] (default: no limit beyond friction).

    Returns
    -------
    TurnFeasibility

    Raises
    ------
    ValueError
        If a parameter is not finite or outside its range; the message names it.

    Examples
    --------
    >>> r = turn_feasibility(entry_speed_mps=14.0, radius_m=28.0, turn_angle_rad=math.pi / 2,
    ...     turn_start_ahead_m=20.0, clothoid_m=0.0, mu_before=0.4, mu_turn=0.4,
    ...     friction_change_ahead_m=0.0, utilization_factor=0.9, dead_time_s=0.0,
    ...     lane_width_m=3.5, vehicle_width_m=2.6, vehicle_length_m=6.28)
    >>> r.feasibility_class.value, round(r.centreline.limit_speed_mps, 2)  # √(0.9·0.4·9.81·28)
    ('feasible', 9.94)
    """
    checks = {
        "entry_speed_mps": entry_speed_mps, "radius_m": radius_m, "mu_before": mu_before,
        "mu_turn": mu_turn, "lane_width_m": lane_width_m, "vehicle_width_m": vehicle_width_m,
        "vehicle_length_m": vehicle_length_m,
    }
    for name, value in checks.items():
        require_positive(name, value)
    for name, value in (("turn_start_ahead_m", turn_start_ahead_m), ("clothoid_m", clothoid_m),
                        ("dead_time_s", dead_time_s)):
        require_positive(name, value, allow_zero=True)
    require_fraction("utilization_factor", utilization_factor)
    if not (math.isfinite(turn_angle_rad) and 0.0 < turn_angle_rad <= math.pi):
        raise ValueError(f"turn_angle_rad must be in (0, π], got {turn_angle_rad!r}")
    if not math.isfinite(friction_change_ahead_m):
        raise ValueError(f"friction_change_ahead_m must be finite, got {friction_change_ahead_m!r}")
    if not max_decel_mps2 > 0.0:
        raise ValueError(f"max_decel_mps2 must be > 0, got {max_decel_mps2!r}")
    if vehicle_width_m > lane_width_m:
        raise ValueError(f"vehicle_width_m must not exceed lane_width_m={lane_width_m}, "
                         f"got {vehicle_width_m!r}")
    arc_angle = turn_angle_rad - clothoid_m / radius_m
    if arc_angle < 0.0:
        # The two clothoids turn by clothoid_m / radius_m together.
        raise ValueError(f"clothoid_m must be <= radius_m * turn_angle_rad = "
                         f"{radius_m * turn_angle_rad:.3f} m, got {clothoid_m!r}")

    def mu_of(s_m: float) -> float:
        return mu_before if s_m < friction_change_ahead_m else mu_turn

    play = 0.5 * (lane_width_m - vehicle_width_m)
    play_outer = play - vehicle_length_m**2 / (8.0 * radius_m)
    shift, tangent_offset = clothoid_offsets_m(radius_m, clothoid_m)
    common = dict(change_m=friction_change_ahead_m, entry_speed_mps=entry_speed_mps,
                  lam=utilization_factor, dead_time_s=dead_time_s, max_decel_mps2=max_decel_mps2)

    def line(radius: float) -> list[tuple[float, float, float]]:
        k = 1.0 / radius
        pieces = [(turn_start_ahead_m, 0.0, 0.0), (clothoid_m, 0.0, k), (radius * arc_angle, k, k),
                  (clothoid_m, k, 0.0)]
        return [p for p in pieces if p[0] > 0.0]

    r_cut = effective_radius_m(radius_m, turn_angle_rad, play, play_outer, shift)
    cut_offset = (play + play_outer + shift) / (1.0 - math.cos(0.5 * turn_angle_rad))
    cut_start = max(turn_start_ahead_m + tangent_offset
                    - cut_offset * math.sin(0.5 * turn_angle_rad), 0.0)
    curve_end = turn_start_ahead_m + 2.0 * clothoid_m + radius_m * arc_angle
    # On the cut circle μ is the lowest the road has from the circle's start to the curve's end.
    mu_cut = min(mu_of(cut_start), mu_of(max(curve_end - 1e-9, cut_start)))

    def mu_cut_of(s_m: float) -> float:
        return mu_of(s_m) if s_m < cut_start else mu_cut

    cut_pieces = [(cut_start, 0.0, 0.0), (r_cut * turn_angle_rad, 1.0 / r_cut, 1.0 / r_cut)]
    if play_outer < 0.0:  # the footprint does not fit the curve even on the centreline
        centreline = with_play = _unfit(entry_speed_mps, radius_m)
    else:
        centreline = _assess("centreline", radius_m, line(radius_m), mu_of, **common)
        r_outer = radius_m + play_outer
        outer = _assess("outer", r_outer, line(r_outer), mu_of, **common)
        cut = _assess("cut", r_cut, [p for p in cut_pieces if p[0] > 0.0], mu_cut_of, **common)
        # The cut circle turns in earlier: for curves of more than 2·atan(1/2) ≈ 53° that costs a
        # braking-limited entry more than its larger radius gains (docs/feasibility.md).
        with_play = max(centreline, outer, cut, key=lambda limit: limit.max_entry_speed_mps)
    if centreline.feasibility_class is FeasibilityClass.FEASIBLE:
        verdict = FeasibilityClass.FEASIBLE
    elif with_play.feasibility_class is FeasibilityClass.INFEASIBLE:
        verdict = FeasibilityClass.INFEASIBLE
    else:
        verdict = FeasibilityClass.MARGINAL
    return TurnFeasibility(
        feasibility_class=verdict, margin_mps=centreline.margin_mps,
        entry_speed_mps=entry_speed_mps, centreline=centreline, with_play=with_play,
        play_inner_m=play, play_outer_m=play_outer, clothoid_shift_m=shift,
        dead_time_s=dead_time_s, utilization_factor=utilization_factor,
    )


def _unfit(entry_speed_mps: float, radius_m: float) -> TurnLimit:
    return TurnLimit(
        path="centreline", radius_m=radius_m, limit_speed_mps=0.0, limit_distance_m=0.0,
        max_entry_speed_mps=0.0, braking_distance_m=math.inf, spare_distance_m=-math.inf,
        margin_mps=-entry_speed_mps, feasibility_class=FeasibilityClass.INFEASIBLE,
    )
