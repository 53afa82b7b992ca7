"""Guards at the planner's boundary: the friction estimate going in, the solution coming out.

**μ̂ sanitisation rule** (applied to every value the planner reads from ``mu_hat_of_s``):

* finite and in ``[MU_MIN, MU_MAX]`` = [0.05, 2]: used as it is;
* finite and in ``(0, MU_MIN)`` or above ``MU_MAX``: clipped to that range;
* non-finite or ≤ 0: the previous planning step's (already sanitised) profile at the same ``s``
  (held constant beyond its ends); without a previous profile, ``SafetySettings.mu_floor``
  (default 0.1, a slippery road);
* a friction source that raises, or returns something that does not broadcast to the queried
  positions: every value is treated as non-finite (and a warning is logged).

Every replaced or clipped value counts; :attr:`Plan.mu_sanitized_stages` reports the count for
the stages of the final solve.

**Solution check** (:func:`check_solution`): a solver's "success" is used only if it is finite,
its front forces lie within the front friction polygons, its rear forces within the rear ones
(at stage 0 the rear's longitudinal force only: its lateral force is the measured state's) and
its longitudinal forces within the actuator bounds (each up to a tolerance), and its states
are plausible: speed within ``[0, MAX_SPEED_MPS]``, ``d`` within the corridor and the heading
error bounded (tolerances in :class:`~mufusion.planner.config.PlausibilityLimits`).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mufusion.planner.ocp import (
    MAX_SPEED_MPS,
    MU_MAX,
    MU_MIN,
    PlausibilityLimits,
    axle_loads_n,
    longitudinal_force_bounds_n,
    plan_polygon_radii_n,
    plan_rear_stiffness,
    polygon_directions,
)
from mufusion.planner.plan import FallbackReason, StageParameters
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import Input, State, rear_lateral_force_n

_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class FrictionProfile:
    """A sanitised μ̂ profile: values ``mu`` at increasing positions ``s_m`` [m]."""

    s_m: np.ndarray
    mu: np.ndarray

    @classmethod
    def from_stages(cls, s_m: np.ndarray, mu: np.ndarray) -> FrictionProfile:
        """Profile from per-stage values (sorted by position, so it can be interpolated)."""
        order = np.argsort(np.asarray(s_m, dtype=float), kind="stable")
        return cls(np.asarray(s_m, dtype=float)[order], np.asarray(mu, dtype=float)[order])

    def at(self, s_m: np.ndarray) -> np.ndarray:
        """Linear interpolation, held constant beyond the ends."""
        return np.interp(s_m, self.s_m, self.mu)


def sanitize_mu(
    raw: np.ndarray, s_m: np.ndarray, previous: FrictionProfile | None, floor: float
) -> tuple[np.ndarray, int]:
    """Apply the module's rule to ``raw`` μ̂ at positions ``s_m``.

    Parameters
    ----------
    raw
        Values from the friction source, same shape as ``s_m`` (may hold NaN, inf, ≤ 0).
    s_m
        Positions [m].
    previous
        The previous step's sanitised profile, or ``None``.
    floor
        Value for a bad stage that no previous profile covers.

    Returns
    -------
    mu, count
        Sanitised values and how many were replaced or clipped.

    Examples
    --------
    >>> mu, n = sanitize_mu(np.array([0.8, np.nan, 3.0, 0.01]), np.arange(4.0), None, 0.1)
    >>> mu.tolist(), n
    ([0.8, 0.1, 2.0, 0.05], 3)
    """
    raw = np.asarray(raw, dtype=float)
    if raw.size and MU_MIN <= raw.min() and raw.max() <= MU_MAX:
        # The usual case (NaN fails both comparisons): nothing to replace or clip.
        return raw.copy(), 0
    bad = ~np.isfinite(raw) | (raw <= 0.0)
    with np.errstate(invalid="ignore"):
        clipped = ~bad & ((raw < MU_MIN) | (raw > MU_MAX))
    mu = np.clip(np.where(bad, MU_MIN, raw), MU_MIN, MU_MAX)
    if np.any(bad):
        fill = previous.at(s_m) if previous is not None else np.full(np.shape(s_m), floor)
        mu = np.where(bad, np.clip(fill, MU_MIN, MU_MAX), mu)
    return mu, int(np.count_nonzero(bad) + np.count_nonzero(clipped))


class SanitizedFriction:
    """``mu_hat_of_s`` with the sanitisation rule applied; never raises.

    ``last_count`` is the number of values replaced or clipped in the latest call.
    """

    def __init__(
        self,
        mu_hat_of_s: Callable[[np.ndarray], np.ndarray],
        previous: FrictionProfile | None,
        floor: float,
    ) -> None:
        self._source = mu_hat_of_s
        self._previous = previous
        self._floor = floor
        self.last_count = 0

    def __call__(self, s_m: np.ndarray) -> np.ndarray:
        s = np.asarray(s_m, dtype=float)
        try:
            raw = np.asarray(self._source(s), dtype=float)
            if raw.shape != s.shape:
                raw = np.broadcast_to(raw, s.shape)
        except Exception as exc:  # a broken friction source degrades, never raises
            _log.warning("friction estimate unusable (%r); sanitising every stage", exc)
            raw = np.full(s.shape, np.nan)
        if raw.size and MU_MIN <= raw.min() and raw.max() <= MU_MAX:
            # sanitize_mu's usual case, without its call (the sampling roll-outs ask 40 times
            # per planning step).
            self.last_count = 0
            return raw.copy()
        mu, self.last_count = sanitize_mu(raw, s, self._previous, self._floor)
        return mu


def judged_rear_rows_n(
    states: np.ndarray, inputs: np.ndarray, stage: StageParameters,
    params: VehicleParams, normals: np.ndarray, *, load_transfer: bool,
    rear_saturation: bool = False,
) -> np.ndarray:
    """The rear polygon's rows ``(n_sides, N)`` [N] of a solution as :func:`check_solution` judges
    them: ``normals @ (F_xr, F_yr)`` with the linear rear tire's ``F_yr`` at the plan's states
    (with ``rear_saturation``, the saturated tire's as the OCP's rear rows price it,
    docs/decisions/0109), except at stage 0, where only the solver's ``F_xr`` counts.

    Stage 0's rear lateral force is the measured state's: no solution can change it, and a
    vehicle whose rear slides puts it far outside the polygon (the linear tire). Judged there,
    every plan of a sliding vehicle is rejected, exactly when it needs one (docs/decisions/0051,
    "A check that judges the solver").
    """
    us = np.asarray(inputs, dtype=float)
    stiffness = plan_rear_stiffness(stage.rear_stiffness_n_per_rad, stage.fzr_n, us.T, params,
                                    load_transfer)
    limit = None
    if rear_saturation:  # the dynamics' force (PlannerConfig.rear_saturation)
        limit = stage.mu_hat * (axle_loads_n(us, params)[1] if load_transfer else stage.fzr_n)
    fyr = rear_lateral_force_n(np.asarray(states)[:-1].T, stiffness, params, limit)
    fyr[0] = 0.0
    return normals @ np.stack([np.asarray(inputs)[:, Input.fxr], fyr])


def judge_solution(
    states: np.ndarray,
    inputs: np.ndarray,
    stage: StageParameters,
    d_lo: np.ndarray,
    d_hi: np.ndarray,
    params: VehicleParams,
    n_sides: int,
    limits: PlausibilityLimits,
    *,
    load_transfer: bool,
    rear_saturation: bool = False,
) -> tuple[FallbackReason, tuple[str, ...]]:
    """Whether a solution may be used, and the checks it fails.

    Parameters
    ----------
    states, inputs
        The solution, ``(N+1, 6)`` and ``(N, 3)``.
    stage
        The stage parameters of the solve (:func:`~mufusion.planner.ocp.stage_parameters`).
    d_lo, d_hi
        The corridor of the solve at stages 1..N [m].
    params
        Vehicle parameters.
    n_sides
        Friction-polygon sides.
    limits
        Tolerances.
    load_transfer
        Whether the polygons' radii followed the plan's own longitudinal forces
        (``PlannerConfig.load_transfer``).

    Returns
    -------
    reason, failed
        ``NONE``, ``NON_FINITE`` or ``IMPLAUSIBLE``, and the checks a finite solution fails, in
        this order: ``"front polygon"``, ``"rear polygon"``, ``"longitudinal force bounds"``,
        ``"speed"``, ``"corridor"``, ``"heading error"`` (empty: none, or not finite).
    """
    xs, us = np.asarray(states, dtype=float), np.asarray(inputs, dtype=float)
    if not (np.isfinite(xs).all() and np.isfinite(us).all()):
        return FallbackReason.NON_FINITE, ()
    normals, ratio = polygon_directions(n_sides)
    radius_front, radius_rear = plan_polygon_radii_n(us, stage, params, load_transfer)
    front = normals @ np.stack([us[:, Input.fxf], us[:, Input.fyf]])
    rear = judged_rear_rows_n(xs, us, stage, params, normals, load_transfer=load_transfer,
                              rear_saturation=rear_saturation)
    lower, upper = longitudinal_force_bounds_n(params)
    slack = limits.force_bound_tolerance * np.maximum(np.abs(lower), np.abs(upper))
    fx = us[:, [Input.fxf, Input.fxr]]
    vx, d, dpsi = xs[:, State.vx], xs[1:, State.d], xs[:, State.dpsi]
    reasons = {
        "front polygon": (
            front > (ratio + limits.front_polygon_tolerance) * radius_front
        ).any(),
        "rear polygon": (
            rear > (ratio + limits.rear_polygon_tolerance) * radius_rear
        ).any(),
        "longitudinal force bounds": ((fx < lower - slack) | (fx > upper + slack)).any(),
        "speed": (
            (vx < -limits.speed_tolerance_mps)
            | (vx > MAX_SPEED_MPS + limits.speed_tolerance_mps)
        ).any(),
        "corridor": (
            (d < d_lo - limits.corridor_tolerance_m) | (d > d_hi + limits.corridor_tolerance_m)
        ).any(),
        "heading error": (np.abs(dpsi) > limits.max_heading_error_rad).any(),
    }
    failed = tuple(name for name, bad in reasons.items() if bad)
    if failed:
        _log.warning("planner solution rejected: outside the %s", ", ".join(failed))
        return FallbackReason.IMPLAUSIBLE, failed
    return FallbackReason.NONE, ()


SOFT_CHECKS = frozenset({"rear polygon", "corridor"})
"""The checks of :func:`judge_solution` on the OCP's soft rows: a solution outside them by
more than the tolerance traded its slack for the rest (a plan at the edge of what it can do), it
did not diverge; every other check is on a hard constraint or the state's plausibility."""


def check_solution(
    states: np.ndarray,
    inputs: np.ndarray,
    stage: StageParameters,
    d_lo: np.ndarray,
    d_hi: np.ndarray,
    params: VehicleParams,
    n_sides: int,
    limits: PlausibilityLimits,
    *,
    load_transfer: bool,
) -> FallbackReason:
    """``FallbackReason.NONE`` if a solution may be used, else why not (``NON_FINITE`` or
    ``IMPLAUSIBLE``): :func:`judge_solution`'s reason."""
    return judge_solution(states, inputs, stage, d_lo, d_hi, params, n_sides, limits,
                          load_transfer=load_transfer)[0]
