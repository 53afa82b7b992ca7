"""Shared pieces of the feasibility oracle: the verdict, its marginal band, input checks."""

from __future__ import annotations

import math
from enum import Enum

GRAVITY_MPS2 = 9.81

MARGINAL_BAND_FRACTION = 0.05
"""Half-width of the marginal band, as a fraction of the entry speed [-].

A variant is *feasible* when its speed margin is at least 5 % of the entry speed, *infeasible*
when it misses by more than 5 %, *marginal* in between. The point mass leaves out effects worth
a few per cent of speed: the planner's 12-sided friction polygon grants ``cos(π/12) = 0.966`` of
the λ-circle in pure braking or pure cornering (−1.7 % of a curve's limit speed, +3.5 % of a
braking distance); a plan is applied up to one planning period (0.1 s) after its state was
measured, an extra dead time worth ``a·0.1 s`` ≈ 0.2–0.9 m/s at the decelerations of the
published grids (2–5 % of 14–20 m/s); and the yaw transient and tire force build-up at the
curve's entry or the evasion's start take a few tenths of a second the point mass does not need.
"""


class FeasibilityClass(str, Enum):
    """Physics verdict on one variant (ordered: infeasible < marginal < feasible)."""

    INFEASIBLE = "infeasible"
    MARGINAL = "marginal"
    FEASIBLE = "feasible"

    @property
    def rank(self) -> int:
        """0 (infeasible), 1 (marginal) or 2 (feasible): comparable verdicts."""
        return {"infeasible": 0, "marginal": 1, "feasible": 2}[self.value]


def classify_speed_margin(margin_mps: float, speed_mps: float) -> FeasibilityClass:
    """Class of a speed margin with the band :data:`MARGINAL_BAND_FRACTION` × ``speed_mps``.

    Parameters
    ----------
    margin_mps
        Highest speed at which the manoeuvre fits minus the actual speed [m/s]; may be ±inf.
    speed_mps
        The actual (entry) speed [m/s], > 0.

    Returns
    -------
    FeasibilityClass

    Examples
    --------
    >>> classify_speed_margin(0.5, 14.0).value, classify_speed_margin(0.8, 14.0).value
    ('marginal', 'feasible')
    """
    band = MARGINAL_BAND_FRACTION * speed_mps
    if margin_mps >= band:
        return FeasibilityClass.FEASIBLE
    if margin_mps < -band:
        return FeasibilityClass.INFEASIBLE
    return FeasibilityClass.MARGINAL


def require_positive(name: str, value: float, *, allow_zero: bool = False) -> None:
    """Raise ValueError naming ``name`` unless ``value`` is finite and > 0 (≥ 0 if allowed)."""
    ok = math.isfinite(value) and (value >= 0.0 if allow_zero else value > 0.0)
    if not ok:
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{name} must be a finite number {bound}, got {value!r}")


def require_fraction(name: str, value: float) -> None:
    """Raise ValueError naming ``name`` unless ``value`` is in (0, 1]."""
    if not (math.isfinite(value) and 0.0 < value <= 1.0):
        raise ValueError(f"{name} must be in (0, 1], got {value!r}")
