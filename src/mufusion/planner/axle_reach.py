"""The braking a two-axle vehicle has left while cornering: its g-g diagram with load transfer.

The speed reference's braking ramps (:mod:`mufusion.planner.speed_profile`) are the point
mass's: at lateral acceleration ``a_y`` it brakes with ``√(a² − a_y²)``, ``a = λ' μ̂ g``. A
vehicle brakes with two axles whose loads move: decelerating at ``d`` moves ``m d h / L`` from
the rear axle to the front, while the steady turn loads each axle laterally in its static share
(moment balance about the centre of gravity: ``F_yf = m a_y l_r / L``, ``F_yr = m a_y l_f /
L``). With each axle's force within the friction ``a/g`` of its own load and the braking split
between the axles as suits them (the planner's forces are per axle), ``d`` is reachable iff

    d/a ≤ √((p + η d/a)² − (r p)²) + √((q − η d/a)² − (r q)²),

``r = a_y / a``, ``p = l_r / L`` and ``q = l_f / L`` the axles' static shares, ``η = (a/g)
(h / L)``. The right side is concave in ``d`` and equals ``√(1 − r²)`` at ``d = 0`` (the point
mass's reach), so the reachable decelerations are an interval ``[0, d*]`` and ``d*`` is never
above the point mass's. This is the quasi-steady-state g-g diagram of lap-time simulation
(Brayshaw & Harrison 2005; Lovato & Massaro 2022) for a rigid two-axle body without lateral
load transfer between the wheels of an axle (the planner's single-track model has none either).

The truck (h 1.0 m on a 3.4 m wheelbase, rear share 0.355) at ``a/g`` 0.9 and half its
lateral reach has 0.67 of the friction left for braking where the point mass has 0.87; at
0.7 of the lateral reach 0.40 against 0.71. The car (h 0.57 m, L 2.58 m): 0.83 and 0.63.
A reference braking with the point mass's reach asks the truck on a curve's clothoid for
decelerations its unloaded rear cannot give beside the curve's lateral force; braking with
this reach instead (``planner.reference_load_transfer``) was measured and not adopted: it
moves which narrow-lane and hairpin trucks leave their lane by centimetres, not how many
(docs/decisions/0106).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mufusion.vehicle.params import GRAVITY_MPS2, VehicleParams

BISECTION_STEPS = 32
"""Halvings of the bracket on ``d/a`` (at most 1 wide): ``d*`` to within 2.3e-10 of ``a``,
from below (the reach returned is always reachable)."""


@dataclass(frozen=True)
class PitchTransfer:
    """What moves load between the axles under braking (dimensionless, from the vehicle's
    geometry): the front axle's static share ``l_r / L`` and the centre of gravity's height per
    wheelbase ``h / L``."""

    front_share: float
    height_per_wheelbase: float

    def __post_init__(self) -> None:
        if not 0.0 < self.front_share < 1.0:
            raise ValueError(f"front_share must be in (0, 1), got {self.front_share!r}")
        if not 0.0 <= self.height_per_wheelbase <= 2.0:
            raise ValueError("height_per_wheelbase must be in [0, 2], got "
                             f"{self.height_per_wheelbase!r}")

    @classmethod
    def of(cls, params: VehicleParams) -> PitchTransfer:
        """The transfer of the vehicle ``params`` describes."""
        return cls(params.cog_to_rear_axle_m / params.wheelbase_m,
                   params.cog_height_m / params.wheelbase_m)


def two_axle_braking_mps2(accel_mps2: float, lateral_mps2: float,
                          transfer: PitchTransfer) -> float:
    """The highest deceleration [m/s²] the two axles reach while cornering at ``lateral_mps2``
    on friction ``accel_mps2`` (the circle's radius ``a``, each axle's force within ``a/g`` of
    its load), never above the point mass's ``√(a² − a_y²)``; ``a`` without cornering, 0 where
    the lateral demand (either sign) is ``a`` or more or ``a`` is not positive.

    The same operations, in the same order, as the compiled passes'
    (``mufusion.planner._speed_profile_c``): their results agree bit for bit.

    Examples
    --------
    >>> truck = PitchTransfer(0.645, 0.294)
    >>> a = 0.9 * 9.81
    >>> round(two_axle_braking_mps2(a, 0.5 * a, truck) / a, 3), round((1 - 0.25) ** 0.5, 3)
    (0.671, 0.866)
    >>> two_axle_braking_mps2(a, 0.0, truck) == a  # no cornering: the whole circle
    True
    >>> two_axle_braking_mps2(a, 0.0, PitchTransfer(0.645, 0.0)) == a
    True
    """
    if accel_mps2 <= 0.0:
        return 0.0
    r = lateral_mps2 / accel_mps2
    if r < 0.0:
        r = -r
    if r >= 1.0:
        return 0.0
    if r == 0.0:
        return accel_mps2
    p = transfer.front_share
    q = 1.0 - p
    eta = accel_mps2 / GRAVITY_MPS2 * transfer.height_per_wheelbase
    hi = math.sqrt(1.0 - r * r)
    # The rear axle holds its lateral share only while it keeps (1 − r) of its static load.
    if eta > 0.0 and q * (1.0 - r) / eta < hi:
        hi = q * (1.0 - r) / eta
    if _reach_left(hi, r, p, q, eta) >= 0.0:
        return accel_mps2 * hi
    lo = 0.0
    for _ in range(BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        if _reach_left(mid, r, p, q, eta) >= 0.0:
            lo = mid
        else:
            hi = mid
    return accel_mps2 * lo


def _reach_left(b: float, r: float, p: float, q: float, eta: float) -> float:
    """The axles' braking reach at ``d/a = b`` less ``b`` (≥ 0: ``b`` is reachable)."""
    front = p + eta * b
    rear = q - eta * b
    rear_sq = rear * rear - (r * q) * (r * q)
    return (math.sqrt(front * front - (r * p) * (r * p))
            + math.sqrt(rear_sq if rear_sq > 0.0 else 0.0) - b)
