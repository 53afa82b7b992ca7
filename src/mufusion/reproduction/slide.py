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

from mufusion.metrics.run_metrics import SPIN_BODY_SLIP_RAD
from mufusion.reproduction.graded import SATURATION, lane_excursion_m
from mufusion.sim.log import RunLog
from mufusion.vehicle.params import GRAVITY_MPS2

__all__ = ["SATURATION", "SlideDiagnosis", "executed_stage", "slide_diagnosis", "slide_text"]
EXCITATION = 0.5
"""Utilisation above which the paper's local estimator can measure friction [-]."""
ESTIMATE_TOLERANCE = 0.1
"""|μ̂ − μ_gt| under the vehicle within which the estimate counts as having dropped to the truth."""
SLIDE_WINDOW_S = 0.5
"""A lane exit counts as carried by a slide if an axle was saturated this long before it [s]."""


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
    lane_excursion_m
        Farthest footprint corner beyond the ego lane's edges (negative: room left inside).
    lane_margin_m
        Lane room on each side of a centred vehicle, ``(lane width − vehicle width)/2``.
    heading_at_exit_rad
        Heading error to the lane when a corner first left it (``None`` if it never did).
    sliding_axle_at_exit
        ``"front"`` or ``"rear"``: the axle saturated within :data:`SLIDE_WINDOW_S` before the
        first lane exit (the front if both), ``None`` if neither (or no exit).
    peak_util_front
        Largest realised front-tire utilisation.
    saturated_t_s, saturated_duration_s
        First tick with front utilisation ≥ :data:`SATURATION`, and the time spent there.
    peak_util_rear, rear_saturated_t_s
        The same for the rear axle: its peak, and when it first saturated (a rear that slides
        first spins the vehicle).
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
    curve_entry_t_s, curve_entry_speed_mps, curve_limit_speed_mps
        When the centre of gravity first reached a curved part of the road, its speed then,
        and the speed at which the true μ there holds the curve's radius at full utilisation
        without braking, ``sqrt(μ_gt g / |κ|)`` (``None`` on a straight road).
    mu_hat_at_curve_entry
        μ̂ under the vehicle at the planning step nearest the curve entry.
    final_speed_mps
        Speed at the end of the run.
    exit_on_curve
        Whether the road curved where a corner first left the lane (``None`` if it never did).
    """

    configuration: str
    left_lane: bool
    lane_exit_t_s: float | None
    entered_opposing_lane: bool
    opposing_t_s: float | None
    max_abs_offset_m: float
    max_outward_offset_m: float
    lane_excursion_m: float
    lane_margin_m: float
    heading_at_exit_rad: float | None
    sliding_axle_at_exit: str | None
    peak_util_front: float
    saturated_t_s: float | None
    saturated_duration_s: float
    peak_util_rear: float
    rear_saturated_t_s: float | None
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
    curve_entry_t_s: float | None = None
    curve_entry_speed_mps: float | None = None
    curve_limit_speed_mps: float | None = None
    mu_hat_at_curve_entry: float | None = None
    exit_on_curve: bool | None = None

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


def _curve_entry(log: RunLog, stage: pd.DataFrame) -> dict[str, float | None]:
    ts, road = log.timeseries, log.meta.road
    kappa = np.interp(ts["s_m"].to_numpy(dtype=float), road.s_m, road.curvature_1pm)
    curved = np.abs(kappa) > 1e-6
    if not curved.any():
        return {}
    i = int(np.argmax(curved))
    t_entry = float(ts["t_s"].iloc[i])
    mu_true = float(np.interp(ts["s_m"].iloc[i], road.s_m, road.mu))
    # The curve's tightest radius: the arc's, after any clothoid.
    kappa_max = float(np.max(np.abs(road.curvature_1pm)))
    mu_hat = None
    if len(stage):
        nearest = int(np.argmin(np.abs(stage["t_s"].to_numpy() - t_entry)))
        mu_hat = float(stage["mu_hat"].iloc[nearest])
    return {
        "curve_entry_t_s": t_entry,
        "curve_entry_speed_mps": float(ts["speed_mps"].iloc[i]),
        "curve_limit_speed_mps": float(np.sqrt(mu_true * GRAVITY_MPS2 / kappa_max)),
        "mu_hat_at_curve_entry": mu_hat,
    }


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
    util_rear = ts["util_rear"].to_numpy(dtype=float)
    exit_t = _first(t, left)
    heading, sliding_axle, on_curve = None, None, None
    with np.errstate(invalid="ignore"):
        saturated = util >= SATURATION
        rear_saturated = util_rear >= SATURATION
    if exit_t is not None:
        first = np.flatnonzero(left)[0]
        heading = float(ts["dpsi_rad"].to_numpy()[first])
        road = log.meta.road
        on_curve = bool(abs(np.interp(float(ts["s_m"].iloc[first]), road.s_m,
                                      road.curvature_1pm)) > 1e-6)
        window = ((t >= exit_t - SLIDE_WINDOW_S) & (t <= exit_t)).to_numpy()
        for axle, flags in (("front", saturated), ("rear", rear_saturated)):
            if (flags & window).any():
                sliding_axle = axle
                break
    stage = executed_stage(log)
    ratio = stage["planned_ratio"].to_numpy(dtype=float)
    steps = log.planning_steps
    steps = steps[steps["t_s"] >= 0.0] if not steps.empty else steps
    near = np.abs(stage["mu_hat"].to_numpy() - stage["mu_true"].to_numpy())
    return SlideDiagnosis(
        configuration=log.meta.configuration,
        left_lane=bool(left.any()),
        lane_exit_t_s=exit_t,
        entered_opposing_lane=bool(opposing.any()),
        opposing_t_s=_first(t, opposing),
        max_abs_offset_m=float(np.max(np.abs(ts["d_m"]))),
        max_outward_offset_m=float(np.max(ts["d_m"])),
        lane_excursion_m=lane_excursion_m(log),
        lane_margin_m=0.5 * (log.meta.road.lane_width_m - log.meta.vehicle.width_m),
        heading_at_exit_rad=heading,
        sliding_axle_at_exit=sliding_axle,
        peak_util_front=float(np.nanmax(util)),
        saturated_t_s=_first(t, saturated),
        saturated_duration_s=float(saturated.sum()) * _step(t),
        peak_util_rear=float(np.nanmax(util_rear)),
        rear_saturated_t_s=_first(t, rear_saturated),
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
        exit_on_curve=on_curve,
        **_curve_entry(log, stage),
    )


def _at(t: float | None) -> str:
    return "never" if t is None else f"at t = {t:.2f} s"


def slide_text(diag: SlideDiagnosis) -> str:
    """Why the run left its lane, or why not, in a few sentences from :func:`slide_diagnosis`.

    Examples
    --------
    >>> d = SlideDiagnosis(
    ...     configuration="L", left_lane=False, lane_exit_t_s=None, entered_opposing_lane=False,
    ...     opposing_t_s=None, max_abs_offset_m=0.2, max_outward_offset_m=0.2,
    ...     lane_excursion_m=-0.1, lane_margin_m=0.45, heading_at_exit_rad=None,
    ...     sliding_axle_at_exit=None,
    ...     peak_util_front=0.9, saturated_t_s=None, saturated_duration_s=0.0,
    ...     peak_util_rear=0.8, rear_saturated_t_s=None, excited_t_s=1.0, over_limit_t_s=None,
    ...     over_limit_duration_s=0.0, peak_planned_ratio=0.8, local_available_t_s=1.2,
    ...     estimate_drop_t_s=1.3, mu_hat_start=0.8, mu_true_start=0.4, peak_body_slip_rad=0.05,
    ...     final_speed_mps=10.0)
    >>> "Neither axle saturated" in slide_text(d) and "stayed in its lane" in slide_text(d)
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
    if diag.curve_entry_speed_mps is not None:
        hat = diag.mu_hat_at_curve_entry
        parts.append(
            f"It reached the curve {_at(diag.curve_entry_t_s)} at "
            f"{diag.curve_entry_speed_mps:.1f} m/s"
            + ("" if hat is None else f" with μ̂ = {hat:.3f} under it")
            + f"; the true friction holds the arc's radius up to "
            f"{diag.curve_limit_speed_mps:.1f} m/s at full utilisation without braking."
        )
    parts.append(_saturation_text(diag))
    parts.append(_lane_text(diag))
    return " ".join(parts)


def _saturation_text(diag: SlideDiagnosis) -> str:
    if not diag.saturated and diag.rear_saturated_t_s is None:
        return (
            f"Neither axle saturated (peak utilisation front {diag.peak_util_front:.2f}, rear "
            f"{diag.peak_util_rear:.2f}); the body slip reached {diag.peak_body_slip_rad:.2f} rad."
        )
    pieces = []
    for name, when in (("front", diag.saturated_t_s), ("rear", diag.rear_saturated_t_s)):
        if when is None:
            continue
        order = ""
        if diag.estimate_drop_t_s is None or when < diag.estimate_drop_t_s:
            order = " (before the estimate dropped)"
        pieces.append(f"the {name} {_at(when)}{order}")
    text = f"The tires saturated (utilisation ≥ {SATURATION}): {' and '.join(pieces)}"
    if diag.saturated:
        text += f"; the front stayed saturated for {diag.saturated_duration_s:.1f} s"
    return text + f". The body slip reached {diag.peak_body_slip_rad:.2f} rad."


def _lane_text(diag: SlideDiagnosis) -> str:
    c = diag.configuration
    where = (
        f"The centre moved up to {diag.max_outward_offset_m:.2f} m towards the opposing lane "
        f"({diag.lane_margin_m:.2f} m of lane on each side of a centred vehicle); the farthest "
        f"corner came {_excursion(diag.lane_excursion_m)}"
    )
    first_slide = min((t for t in (diag.saturated_t_s, diag.rear_saturated_t_s) if t is not None),
                      default=None)
    if not diag.left_lane:
        reason = ("the slide stayed inside the lane" if first_slide is not None
                  else "without a saturated axle there was no slide to carry it out")
        return f"{where}, and {c} stayed in its lane: {reason}.{_in_time(diag)}"
    exit_t = diag.lane_exit_t_s
    if exit_t is None:  # left_lane without a tick: not produced by slide_diagnosis
        return f"{where}."
    axle = diag.sliding_axle_at_exit
    if axle is not None:
        lane = "into the opposing lane" if diag.entered_opposing_lane else "out of its lane"
        spin = " and spun" if diag.peak_body_slip_rad > SPIN_BODY_SLIP_RAD else ""
        return (f"{where}. A corner left the lane {_at(diag.lane_exit_t_s)} with the {axle} "
                f"tires saturated: {c} slid{spin} {lane}.")
    text = (
        f"{where}. A corner first left the lane {_at(diag.lane_exit_t_s)} with a heading error "
        f"of {diag.heading_at_exit_rad:.2f} rad and no axle saturated in the "
        f"{SLIDE_WINDOW_S} s before: the body's yaw against the "
        f"{'curving lane' if diag.exit_on_curve is not False else 'straight lane'}, not a "
        "slide, carried the corner out"
    )
    if first_slide is not None:
        when = "later" if first_slide > exit_t else "earlier, briefly"
        text += f" (the tires saturated {when}, first {_at(first_slide)})"
    return text + "." + _in_time(diag)


def _in_time(diag: SlideDiagnosis) -> str:
    """Why no plan asked for too much: the estimate dropped before the curve was reached."""
    drop, entry = diag.estimate_drop_t_s, diag.curve_entry_t_s
    started_wrong = abs(diag.mu_hat_start - diag.mu_true_start) > ESTIMATE_TOLERANCE
    if (not started_wrong or diag.over_limit_t_s is not None or drop is None or entry is None
            or drop > entry):
        return ""
    return (f" The estimate dropped {entry - drop:.2f} s before the curve began, so no executed "
            "plan asked for more than the true friction.")


def _excursion(excursion_m: float) -> str:
    if excursion_m > 0.0:
        return f"{excursion_m:.2f} m beyond the lane's edge"
    return f"within {-excursion_m:.2f} m of the lane's edge"
