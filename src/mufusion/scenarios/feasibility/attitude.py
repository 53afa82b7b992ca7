"""What the body's attitude in a curve leaves of the lateral friction (the oracle's rigid body).

A vehicle cornering in the steady state turns its body against its path by the rear tire's slip
angle less what the wheelbase's geometry gives back: the heading relative to the lane is
``ψ = α_r − l_r κ`` (nose into the curve; ``l_r``: centre of gravity to the rear axle), and the
rear slip angle ``α_r`` is the one at which the rear tire delivers the lateral utilisation the
turn asks, ``u = v² κ / (μ g)`` (in the steady state each axle carries its static share, so
every axle runs at that utilisation). A footprint of width ``w`` turned by ``ψ`` spans
``w cos ψ + (a_f + a_r) sin ψ`` across the lane, plus the curve's bulge at its ends, and it must
fit the lane (``a_f``, ``a_r``: centre of gravity to the body's front and rear). A soft tire
(the truck's: 7 /rad per unit load) needs 0.18 rad of slip at 0.88 of μ 0.9, and its
6.28 m × 2.6 m body at that attitude spans 3.51 m: it cannot corner at the planner's
utilisation on a dry road inside a 3.5 m lane, wherever its centre is (docs/decisions/0079,
0090). The cap found here bounds the point mass's lateral acceleration in the oracle's speed
profile (:func:`~mufusion.scenarios.feasibility.profile.backward_profile`); where the tire peaks
before the body fills the lane (the car; low friction) it is 1 and the verdict is the point
mass's. (The planner bounds its curve speeds the same way on its own linear tire and corridor:
:mod:`mufusion.planner.body_fit`.)
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

from scipy.optimize import brentq, minimize_scalar

from mufusion.vehicle.params import TireParams, VehicleParams
from mufusion.vehicle.tires import tire_forces_scalar

_PEAK_SEARCH_RAD = 1.5
"""Upper end of the search for the tire's peak slip angle per unit of μ [rad]."""


def footprint_span_m(heading_rad: float, curvature_1pm: float, width_m: float,
                     front_m: float, rear_m: float) -> float:
    """Width [m] a rectangular body spans across a lane of curvature ``curvature_1pm`` when
    turned by ``heading_rad`` against it at its reference point.

    A body point ``x`` ahead of the reference point and ``y`` to its left lies
    ``y cos ψ + x sin ψ − κ x² / 2`` left of the lane's centre line (the lane curves away from a
    straight body's ends); the span is the largest minus the smallest over the body's two long
    sides (their extremes at the corners or, on the inner side, where ``x = sin ψ / κ``).

    Examples
    --------
    >>> footprint_span_m(0.0, 0.0, 2.6, 2.65, 3.63)  # straight: the width
    2.6
    >>> round(footprint_span_m(0.15, 1 / 80, 2.6, 2.65, 3.63), 3)  # the truck at 0.15 rad
    3.548
    """
    psi, k = heading_rad, curvature_1pm
    cos_p, sin_p = math.cos(psi), math.sin(psi)

    def side(y: float) -> list[float]:
        xs = [-rear_m, front_m]
        if k != 0.0 and -rear_m < sin_p / k < front_m:
            xs.append(sin_p / k)  # the side's extreme against the curved lane
        return [y * cos_p + x * sin_p - 0.5 * k * x * x for x in xs]

    points = side(0.5 * width_m) + side(-0.5 * width_m)
    return max(points) - min(points)


@dataclass(frozen=True)
class BodyInLane:
    """The rigid body the lane must hold (SI units): the lane's width, the body's width and
    its ends from the centre of gravity, the rear axle's distance behind it, and the rear tire
    as a function of the road's μ (the plant's, surface-dependent where it is)."""

    lane_width_m: float
    width_m: float
    front_m: float
    rear_m: float
    rear_axle_m: float
    tire_of_mu: Callable[[float], TireParams]

    @classmethod
    def of(cls, params: VehicleParams, lane_width_m: float,
           tire_of_mu: Callable[[float], TireParams] | None = None) -> BodyInLane:
        """The body of ``params`` in a lane ``lane_width_m`` wide (its own tire everywhere
        unless ``tire_of_mu`` says otherwise)."""
        tire = params.tire
        return cls(lane_width_m, params.width_m, params.cog_to_body_front_m,
                   params.cog_to_body_rear_m, params.cog_to_rear_axle_m,
                   tire_of_mu if tire_of_mu is not None else (lambda _mu: tire))

    def lateral_cap(self, mu: float, curvature_1pm: float) -> float:
        """Highest steady lateral utilisation ``v² κ / (μ g)`` at which the body still fits
        the lane on curvature ``curvature_1pm`` [1/m] and friction ``mu`` (1: the tire peaks
        first, or the body fits at no attitude the steady turn can take, which the oracle
        judges elsewhere)."""
        kappa = abs(curvature_1pm)
        heading = _fitting_heading_rad(kappa, self.lane_width_m, self.width_m, self.front_m,
                                       self.rear_m)
        slip = None if heading is None else heading + self.rear_axle_m * kappa
        if slip is None or slip <= 0.0:
            return 1.0
        return _utilization_at(slip, mu, self.tire_of_mu(mu))


@functools.lru_cache(maxsize=65536)
def _fitting_heading_rad(kappa: float, lane_m: float, width_m: float, front_m: float,
                         rear_m: float) -> float | None:
    """The largest heading at which the body spans no more than the lane (None: it does not
    fit at its narrowest attitude, or fits at any heading up to π/4).

    On a curve the body spans least turned slightly nose out of it (its longer rear end then
    swings no further out than its front end bulges), so the search starts there: a body that
    does not fit straight may still fit below the heading a slow turn gives it.
    """
    def excess(psi: float) -> float:
        return footprint_span_m(psi, kappa, width_m, front_m, rear_m) - lane_m

    narrowest = float(minimize_scalar(excess, bounds=(-0.25 * math.pi, 0.25 * math.pi),
                                      method="bounded", options={"xatol": 1e-9}).x)
    if excess(narrowest) >= 0.0 or excess(0.25 * math.pi) <= 0.0:
        return None
    return float(brentq(excess, narrowest, 0.25 * math.pi, xtol=1e-9))


def _utilization_at(slip_angle_rad: float, mu: float, tire: TireParams) -> float:
    """The tire's pure lateral utilisation at ``slip_angle_rad``, held at 1 beyond its peak."""
    if slip_angle_rad >= _peak_slip_angle_rad(tire) * mu:
        return 1.0
    return float(tire_forces_scalar(0.0, slip_angle_rad, 1.0, mu, tire)[2])


@functools.lru_cache(maxsize=256)
def _peak_slip_angle_rad(tire: TireParams) -> float:
    """The pure lateral slip angle of the tire's peak per unit of μ [rad] (the curve depends on
    ``k α / μ`` only)."""
    def slope(alpha: float) -> float:
        h = 1e-6
        return (tire_forces_scalar(0.0, alpha + h, 1.0, 1.0, tire)[2]
                - tire_forces_scalar(0.0, alpha - h, 1.0, 1.0, tire)[2])

    if slope(_PEAK_SEARCH_RAD) > 0.0:
        return _PEAK_SEARCH_RAD
    return float(brentq(slope, 1e-4, _PEAK_SEARCH_RAD, xtol=1e-9))
