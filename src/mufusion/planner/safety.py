"""How the planner and the closed loop react to missing, stale or failing parts.

One settings object for both: the planner reads the friction floor and the minimal-risk
deceleration, the loop the estimate age limit and the fallback count that starts the manoeuvre
(:class:`~mufusion.sim.loop.ClosedLoop`). A scenario's ``[safety]`` table sets it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class SafetySettings:
    """How the loop reacts to missing, stale or failing parts.

    Attributes
    ----------
    max_estimate_age_s
        An estimate older than this is handled like a missing one [s].
    max_consecutive_fallbacks
        After this many planning steps in a row without a usable plan the vehicle enters the
        minimal-risk manoeuvre.
    mu_floor
        Friction assumed where no usable estimate exists [-]: the lowest value the paper's
        camera classes admit (snow/ice, 0.1). The planner uses it for a stage whose μ̂ is not
        finite when no earlier profile covers it; the loop for a missing or stale estimate.
    minimal_risk_decel_fraction
        The minimal-risk manoeuvre brakes at this share of ``μ̂ g`` [-] (the rest stays for
        lane keeping); the planner plans it so (each axle's braking capped at 80 % of its
        limit), and the loop's own lane-keeping braking uses this share of the friction circle
        when no plan can be trusted (braking with what the lane's curvature leaves). 0.8: the
        road's friction is used, not half of it (the vehicle's ABS holds the wheels should μ̂
        over-estimate it).
    """

    max_estimate_age_s: float = 0.35
    max_consecutive_fallbacks: int = 5
    mu_floor: float = 0.1
    minimal_risk_decel_fraction: float = 0.8

    def __post_init__(self) -> None:
        if not (math.isfinite(self.max_estimate_age_s) and self.max_estimate_age_s > 0.0):
            raise ValueError(
                f"max_estimate_age_s must be finite and > 0 s, got {self.max_estimate_age_s!r}"
            )
        if isinstance(self.max_consecutive_fallbacks, bool) or not (
            1 <= self.max_consecutive_fallbacks <= 100
        ):
            raise ValueError(
                "max_consecutive_fallbacks must be in [1, 100], got "
                f"{self.max_consecutive_fallbacks!r}"
            )
        if not 0.05 <= self.mu_floor <= 1.0:
            raise ValueError(f"mu_floor must be in [0.05, 1], got {self.mu_floor!r}")
        if not 0.0 < self.minimal_risk_decel_fraction <= 1.0:
            raise ValueError(
                "minimal_risk_decel_fraction must be in (0, 1], "
                f"got {self.minimal_risk_decel_fraction!r}"
            )
