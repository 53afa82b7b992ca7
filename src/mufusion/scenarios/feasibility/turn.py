"""Turn feasibility: can a point mass on the true μ slow to the curve's limit speed in time?

The curve (a straight, an entry clothoid, a circular arc of radius R, an exit clothoid, together
turning by θ) is followed along the lane centre (*centreline*) or, using the lane's play, along
the better of two lines: the outer edge of the lane (*outer*, radius ``R + p_out`` from the same
turn-in point) and the widest circle through the curve (*cut*, radius R' from the outer edge to
the inner edge at the apex and back, which turns in earlier). Along a line the point mass may use
the acceleration ``λ μ(s) g`` in any direction (λ: the planner's utilisation factor), so its
speed is bounded by ``v² κ(s) ≤ λ μ(s) g`` and, before a tighter point, by braking with what the
lateral demand leaves: ``a_x = √((λμg)² − (v²κ)²)``.
A backward pass from the curve's end (:mod:`~mufusion.scenarios.feasibility.profile`: exact on
straights and arcs, stepped on clothoids) gives the highest speed ``v_max(s)`` from which every
later limit can still be met; μ(s) is the road's along the lane centre, the lower under the two
axles, with the change point mapped onto each line, so a change before, at or inside the curve,
a drop or a rise, is one profile. A first-order actuator lag τ is a dead time τ at the entry
speed before braking starts (its exact response brakes ``a τ²/2`` more: the dead time is
conservative). Derivation and figures: ``docs/feasibility.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.special import fresnel

from mufusion.scenarios.feasibility.attitude import BodyInLane
from mufusion.scenarios.feasibility.common import (
    GRAVITY_MPS2,
    FeasibilityClass,
    classify_speed_margin,
    require_fraction,
    require_positive,
)
from mufusion.scenarios.feasibility.profile import (
    FrictionOfS,
    LateralCap,
    Piece,
    axle_span_friction,
    backward_profile,
    line_position_m,
    lowest_friction,
    max_entry_speed_mps,
)


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
        Distance along the line from the vehicle's start to where that limit first applies [m]:
        the arc's start (the end of the entry clothoid) for the centreline and the outer line,
        the circle's start for the cut; where the friction drops inside the curve, the point at
        which the front axle meets the drop.
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


def line_limit(
    path: Literal["centreline", "outer", "cut"], radius_m: float, pieces: list[Piece],
    mu_of: FrictionOfS, breakpoints: tuple[float, ...], entry_speed_mps: float, lam: float,
    dead_time_s: float, max_decel_mps2: float, lateral_cap: LateralCap | None = None,
) -> TurnLimit:
    """The limit along one line of ``pieces`` from the vehicle's start (s = 0): the backward
    profile (its lateral utilisation bounded by ``lateral_cap`` where that is below λ), the
    highest entry speed cruising through the dead time, the braking point and the margin at
    ``entry_speed_mps``; ``radius_m`` is reported as the line's radius."""
    s, u, limit = backward_profile(pieces, mu_of, breakpoints, lam, max_decel_mps2,
                                   lateral_cap)
    reach = np.minimum.accumulate(u)  # v² allowed for cruising from the start up to s
    v_max = max_entry_speed_mps(s, reach, dead_time_s, math.sqrt(u[0]))
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
    front_axle_ahead_m: float = 0.0,
    rear_axle_behind_m: float = 0.0,
    body: BodyInLane | None = None,
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
    front_axle_ahead_m, rear_axle_behind_m
        Distances of the front and the rear axle from the centre of gravity [m], ≥ 0 (default
        0: a point at the centre of gravity). The point mass has the lower μ under its two
        axles, so a drop acts when the front axle reaches it, a rise once the rear has passed.
    body
        The rigid body the lane must hold (default None: a point mass): the lateral
        utilisation is bounded where the body's attitude on its rear tire's slip would no longer
        fit the lane (:mod:`~mufusion.scenarios.feasibility.attitude`). Judged with the whole
        lane's width on every line, so the lines that use the play (cut, outer) err fast.

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
                        ("dead_time_s", dead_time_s), ("front_axle_ahead_m", front_axle_ahead_m),
                        ("rear_axle_behind_m", rear_axle_behind_m)):
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

    cap: LateralCap | None = None if body is None else body.lateral_cap
    play = 0.5 * (lane_width_m - vehicle_width_m)
    play_outer = play - vehicle_length_m**2 / (8.0 * radius_m)
    shift, tangent_offset = clothoid_offsets_m(radius_m, clothoid_m)

    def assess_line(path: Literal["centreline", "outer", "cut"], radius: float,
                    pieces: list[Piece], mu_of: FrictionOfS,
                    points: tuple[float, ...]) -> TurnLimit:
        return line_limit(path, radius, pieces, mu_of, points, entry_speed_mps,
                          utilization_factor, dead_time_s, max_decel_mps2, cap)

    def friction_on(pieces: list[Piece]) -> tuple[FrictionOfS, tuple[float, ...]]:
        # The road's change point moved onto the line (later on a line outside the centre).
        change = line_position_m(pieces, friction_change_ahead_m)
        return axle_span_friction(mu_before, mu_turn, change, front_axle_ahead_m,
                                  rear_axle_behind_m)

    def line(radius: float) -> list[Piece]:
        k = 1.0 / radius
        pieces = [Piece(turn_start_ahead_m, 0.0, 0.0, turn_start_ahead_m),
                  Piece(clothoid_m, 0.0, k, clothoid_m),
                  Piece(radius * arc_angle, k, k, radius_m * arc_angle),
                  Piece(clothoid_m, k, 0.0, clothoid_m)]
        return [p for p in pieces if p.length_m > 0.0]

    def assess(path: Literal["centreline", "outer"], radius: float) -> TurnLimit:
        pieces = line(radius)
        return assess_line(path, radius, pieces, *friction_on(pieces))

    r_cut = effective_radius_m(radius_m, turn_angle_rad, play, play_outer, shift)
    cut_offset = (play + play_outer + shift) / (1.0 - math.cos(0.5 * turn_angle_rad))
    # The circle leaves the entry straight this far before the curve and, the curve being
    # symmetric, joins the exit straight as far beyond its end.
    cut_lead = cut_offset * math.sin(0.5 * turn_angle_rad) - tangent_offset
    cut_start = max(turn_start_ahead_m - cut_lead, 0.0)
    curve_end = turn_start_ahead_m + 2.0 * clothoid_m + radius_m * arc_angle
    centre_pieces = line(radius_m)
    mu_centre, points = friction_on(centre_pieces)
    # On the cut circle μ is the lowest the road has under the vehicle along the circle's span.
    mu_circle = lowest_friction(mu_centre, cut_start, max(curve_end + cut_lead, cut_start),
                                points)

    def mu_cut_of(s_m: float) -> float:
        return mu_centre(s_m) if s_m < cut_start else mu_circle

    cut_pieces = [Piece(cut_start, 0.0, 0.0, cut_start),
                  Piece(r_cut * turn_angle_rad, 1.0 / r_cut, 1.0 / r_cut,
                        curve_end + cut_lead - cut_start)]
    if play_outer < 0.0:  # the footprint does not fit the curve even on the centreline
        centreline = with_play = _unfit(entry_speed_mps, radius_m)
    else:
        centreline = assess("centreline", radius_m)
        outer = assess("outer", radius_m + play_outer)
        cut = assess_line("cut", r_cut, [p for p in cut_pieces if p.length_m > 0.0],
                          mu_cut_of, (*points, cut_start))
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
