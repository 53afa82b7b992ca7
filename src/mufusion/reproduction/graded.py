"""Graded outcomes of a run, read from its log: how far out, how close, how hard the tires worked.

A yes/no verdict ("left its lane") hides whether a corner grazed the line by a centimetre or the
truck slid across the opposing lane. :func:`graded_outcome` measures it: the farthest footprint
corner beyond the ego lane's edge (the road is rebuilt from the run's validated scenario and the
footprint is placed as the loop places it), the centre's largest offset, the obstacle clearance
or impact speed, and the realised front-tire utilisation.
"""

from __future__ import annotations

from dataclasses import dataclass

from mufusion.metrics import compute_metrics
from mufusion.sim.log import RunLog

SATURATION = 0.98
"""Realised utilisation at which a tire counts as saturated (sliding) [-]."""


@dataclass(frozen=True)
class GradedOutcome:
    """Graded outcome of one run.

    Attributes
    ----------
    max_abs_offset_m
        Largest ``|d|`` of the centre of gravity from the lane centre.
    lane_excursion_m
        Largest distance of a footprint corner beyond the ego lane's edges (either side);
        negative: the smallest room left inside the lane.
    left_lane, entered_opposing_lane, collision
        The yes/no outcomes (as the loop recorded them).
    impact_speed_mps, min_clearance_m
        Speed at the first contact, or the smallest clearance while passing (``None``: none).
    peak_util_front
        Largest realised front-tire utilisation; ``saturated`` if it reached
        :data:`SATURATION`.
    """

    max_abs_offset_m: float
    lane_excursion_m: float
    left_lane: bool
    entered_opposing_lane: bool
    collision: bool
    impact_speed_mps: float | None
    min_clearance_m: float | None
    peak_util_front: float

    @property
    def saturated(self) -> bool:
        return self.peak_util_front >= SATURATION


def lane_excursion_m(log: RunLog) -> float:
    """Largest distance [m] of the footprint beyond the ego lane's edges (negative: inside).

    The loop's recorded lane margin, signed the other way round (``-min lane_margin_m``), so a
    run that keeps every corner 0.1 m inside gives −0.1 and one whose corner crossed the centre
    line by 0.2 m gives 0.2.
    """
    return -float(log.timeseries["lane_margin_m"].min())


def graded_outcome(log: RunLog) -> GradedOutcome:
    """The :class:`GradedOutcome` of a run (from its metrics, :func:`compute_metrics`).

    Raises
    ------
    ValueError
        If the log has no time series.
    """
    m = compute_metrics(log)
    return GradedOutcome(
        max_abs_offset_m=m.max_abs_lateral_offset_m,
        lane_excursion_m=-m.min_lane_margin_m,
        left_lane=m.left_lane,
        entered_opposing_lane=m.entered_opposing_lane,
        collision=m.collision,
        impact_speed_mps=m.impact_speed_mps,
        min_clearance_m=m.min_clearance_m,
        peak_util_front=m.max_front_utilization,
    )
