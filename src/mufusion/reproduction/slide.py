"""The slide mechanism of a lane-keeping run, read from its log (paper Sec. IV-C).

The paper's L "slipped well into the opposing lane": it planned front tire forces beyond the
physical limit and, once its local estimate dropped, could no longer avoid veering out. Whether
a run shows that mechanism is a question for its log:

* the planned force against the true friction circle: the force of the plan's first stage (the
  one the controller executes) over ``μ_gt F_z`` at each planning step (``plans``, stage 0);
* the realised front-tire utilisation (``timeseries.util_front``): saturated at ≥ 0.98;
* when the local estimate became available (``planning_steps.local_available``) and when the
  planner's μ̂ under the vehicle came within :data:`ESTIMATE_TOLERANCE` of the truth;
* the lateral deviation ``d`` and the body slip angle.

:func:`slide_diagnosis` extracts these facts, :func:`slide_text` words them; the figure is
:func:`mufusion.plots.slide.plot_slide`. Nothing here is written for a particular outcome: a
different log gives a different text.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from mufusion.sim.log import RunLog

SATURATION = 0.98
"""Realised utilisation at which a tire counts as saturated (sliding) [-]."""
EXCITATION = 0.5
"""Utilisation above which the paper's local estimator can measure friction [-]."""
ESTIMATE_TOLERANCE = 0.1
"""|μ̂ − μ_gt| under the vehicle within which the estimate counts as having dropped to the truth."""


@dataclass(frozen=True)
class SlideDiagnosis:
    """What one run's log says about a slide (times in s from the start, ``None``: never).

    Attributes
    ----------
    configuration
        The configuration's name (``"L"``).
    left_lane, lane_exit_t_s
        Whether and when a footprint corner first left the ego lane.
    entered_opposing_lane, opposing_t_s
        Whether and when a corner first entered the opposing lane.
    max_abs_offset_m, max_outward_offset_m
        Largest ``|d|``, and largest ``d`` towards the opposing lane (left, positive).
    lane_margin_m
        Lane room on each side of a centred vehicle, ``(lane width − vehicle width)/2``.
    heading_at_exit_rad
        Heading error to the lane when a corner first left it (``None`` if it never did).
    peak_util_front
        Largest realised front-tire utilisation.
    saturated_t_s, saturated_duration_s
        First tick with front utilisation ≥ :data:`SATURATION`, and the time spent there.
    excited_t_s
        First tick with front utilisation > :data:`EXCITATION` (what the local estimator needs).
    over_limit_t_s, over_limit_duration_s, peak_planned_ratio
        The executed planned front force over the true limit ``μ_gt F_z``: first planning step
        above 1, the planning time spent above 1, and the largest ratio.
    local_available_t_s
        First planning step at which the local estimate was available.
    estimate_drop_t_s
        First planning step at which μ̂ under the vehicle was within
        :data:`ESTIMATE_TOLERANCE` of the true μ there.
    mu_hat_start, mu_true_start
        μ̂ and the true μ under the vehicle at the first planning step.
    peak_body_slip_rad
        Largest ``|body slip|``.
    final_speed_mps
        Speed at the end of the run.
    """

    configuration: str
    left_lane: bool
    lane_exit_t_s: float | None
    entered_opposing_lane: bool
    opposing_t_s: float | None
    max_abs_offset_m: float
    max_outward_offset_m: float
    lane_margin_m: float
    heading_at_exit_rad: float | None
    peak_util_front: float
    saturated_t_s: float | None
    saturated_duration_s: float
    excited_t_s: float | None
    over_limit_t_s: float | None
    over_limit_duration_s: float
    peak_planned_ratio: float
    local_available_t_s: float | None
    estimate_drop_t_s: float | None
    mu_hat_start: float
    mu_true_start: float
    peak_body_slip_rad: float
    final_speed_mps: float

    @property
    def saturated(self) -> bool:
        """Whether the front tires ever saturated."""
        return self.saturated_t_s is not None


def executed_stage(log: RunLog) -> pd.DataFrame:
    """Stage 0 of every plan made from the start on (the stage the controller executes), with
    ``planned_ratio`` = ``hypot(F_xf, F_yf) / (μ_gt F_zf)``: 1 is the true friction circle."""
    plans = log.plans
    if plans.empty:
        return plans.assign(planned_ratio=pd.Series(dtype=float))
    first = plans[(plans["k"] == 0) & (plans["t_s"] >= 0.0)].sort_values("t_s").copy()
    force = np.hypot(first["fxf_n"].to_numpy(), first["fyf_n"].to_numpy())
    first["planned_ratio"] = force / (first["mu_true"].to_numpy() * first["fzf_n"].to_numpy())
    return first.reset_index(drop=True)


def _first(times: pd.Series, mask: np.ndarray) -> float | None:
    hit = np.flatnonzero(mask)
    return float(times.iloc[hit[0]]) if hit.size else None


def _step(times: pd.Series) -> float:
    return float(np.median(np.diff(times.to_numpy()))) if len(times) > 1 else 0.0


def slide_diagnosis(log: RunLog) -> SlideDiagnosis:
    """The slide facts of one run (see :class:`SlideDiagnosis`).

    Raises
    ------
    ValueError
        If the log has no time series.
    """
    ts = log.timeseries
    if ts.empty:
        raise ValueError("log has no timeseries rows: nothing to diagnose")
    t = ts["t_s"]
    left = ts["left_lane"].astype(bool).to_numpy()
    opposing = ts["in_opposing_lane"].astype(bool).to_numpy()
    util = ts["util_front"].to_numpy(dtype=float)
    exit_t = _first(t, left)
    heading = None
    if exit_t is not None:
        heading = float(ts["dpsi_rad"].to_numpy()[np.flatnonzero(left)[0]])
    stage = executed_stage(log)
    ratio = stage["planned_ratio"].to_numpy(dtype=float)
    steps = log.planning_steps
    steps = steps[steps["t_s"] >= 0.0] if not steps.empty else steps
    near = np.abs(stage["mu_hat"].to_numpy() - stage["mu_true"].to_numpy())
    with np.errstate(invalid="ignore"):
        saturated = util >= SATURATION
    return SlideDiagnosis(
        configuration=log.meta.configuration.value,
        left_lane=bool(left.any()),
        lane_exit_t_s=exit_t,
        entered_opposing_lane=bool(opposing.any()),
        opposing_t_s=_first(t, opposing),
        max_abs_offset_m=float(np.max(np.abs(ts["d_m"]))),
        max_outward_offset_m=float(np.max(ts["d_m"])),
        lane_margin_m=0.5 * (log.meta.road.lane_width_m - log.meta.vehicle.width_m),
        heading_at_exit_rad=heading,
        peak_util_front=float(np.nanmax(util)),
        saturated_t_s=_first(t, saturated),
        saturated_duration_s=float(saturated.sum()) * _step(t),
        excited_t_s=_first(t, util > EXCITATION),
        over_limit_t_s=_first(stage["t_s"], ratio > 1.0) if len(stage) else None,
        over_limit_duration_s=float((ratio > 1.0).sum()) * _step(stage["t_s"]),
        peak_planned_ratio=float(np.max(ratio)) if ratio.size else 0.0,
        local_available_t_s=(
            _first(steps["t_s"], steps["local_available"].astype(bool).to_numpy())
            if not steps.empty else None
        ),
        estimate_drop_t_s=_first(stage["t_s"], near <= ESTIMATE_TOLERANCE) if len(stage) else None,
        mu_hat_start=float(stage["mu_hat"].iloc[0]) if len(stage) else float("nan"),
        mu_true_start=float(stage["mu_true"].iloc[0]) if len(stage) else float("nan"),
        peak_body_slip_rad=float(np.max(np.abs(ts["body_slip_rad"]))),
        final_speed_mps=float(ts["speed_mps"].iloc[-1]),
    )


def _at(t: float | None) -> str:
    return "never" if t is None else f"at t = {t:.2f} s"


def slide_text(diag: SlideDiagnosis) -> str:
    """Why the run left its lane, or why not, in a few sentences from :func:`slide_diagnosis`.

    Examples
    --------
    >>> d = SlideDiagnosis("L", False, None, False, None, 0.2, 0.2, 0.45, None, 0.9, None, 0.0,
    ...                    1.0, None, 0.0, 0.8, 1.2, 1.3, 0.8, 0.4, 0.05, 10.0)
    >>> "never saturated" in slide_text(d)
    True
    """
    c = diag.configuration
    parts = [
        f"{c} started with μ̂ = {diag.mu_hat_start:.3f} under the vehicle on μ = "
        f"{diag.mu_true_start:.2f}.",
    ]
    if diag.over_limit_t_s is None:
        parts.append(
            f"The executed planned front force never exceeded the true limit μ_gt F_z (peak "
            f"{diag.peak_planned_ratio:.2f} of it)."
        )
    else:
        parts.append(
            f"Its executed planned front force exceeded the true limit μ_gt F_z first "
            f"{_at(diag.over_limit_t_s)}, for {diag.over_limit_duration_s:.1f} s in all, peaking "
            f"at {diag.peak_planned_ratio:.2f} times the limit."
        )
    parts.append(
        f"Realised front utilisation first exceeded {EXCITATION} {_at(diag.excited_t_s)}; the "
        f"local estimate became available {_at(diag.local_available_t_s)} and μ̂ under the "
        f"vehicle came within {ESTIMATE_TOLERANCE} of the truth {_at(diag.estimate_drop_t_s)}."
    )
    if diag.saturated:
        order = ""
        if diag.estimate_drop_t_s is None or diag.saturated_t_s < diag.estimate_drop_t_s:
            order = " before the estimate dropped"
        elif diag.saturated_t_s >= diag.estimate_drop_t_s:
            order = " after the estimate had dropped"
        parts.append(
            f"The front tires saturated (utilisation ≥ {SATURATION}) {_at(diag.saturated_t_s)}"
            f"{order} and stayed saturated for {diag.saturated_duration_s:.1f} s; the body slip "
            f"reached {diag.peak_body_slip_rad:.2f} rad."
        )
    else:
        parts.append(
            f"The front tires never saturated (peak utilisation {diag.peak_util_front:.2f}); the "
            f"body slip reached {diag.peak_body_slip_rad:.2f} rad."
        )
    where = (
        f"The centre moved up to {diag.max_outward_offset_m:.2f} m towards the opposing lane "
        f"({diag.lane_margin_m:.2f} m of lane on each side of a centred vehicle)"
    )
    if not diag.left_lane:
        reason = ("the slide stayed inside the lane" if diag.saturated
                  else "without a saturated front axle there was no slide to carry it out")
        parts.append(f"{where} and {c} stayed in its lane: {reason}.")
    elif diag.saturated and diag.saturated_t_s <= diag.lane_exit_t_s:
        lane = "the opposing lane" if diag.entered_opposing_lane else "its lane"
        parts.append(
            f"{where}; a corner left its lane {_at(diag.lane_exit_t_s)}, after the front "
            f"saturated: {c} slid out of {lane}."
        )
    else:
        parts.append(
            f"{where}; a corner left its lane {_at(diag.lane_exit_t_s)} with a heading error of "
            f"{diag.heading_at_exit_rad:.2f} rad, without a saturated front axle before it: the "
            "body's yaw against the lane, not a slide, carried the corner out."
        )
    return " ".join(parts)
