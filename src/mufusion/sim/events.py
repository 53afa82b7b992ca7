"""The kinds of event the closed loop logs (table ``events``, column ``kind``).

Each value is the string the log holds, so logs written before the kinds were an enum read the
same; compare a log's ``kind`` column with a member (``kinds == EventKind.PROBE_START``).
"""

from __future__ import annotations

from collections.abc import Callable
from enum import StrEnum


class EventKind(StrEnum):
    """What an event reports: a fault, a reaction to one, or a change of control mode."""

    FAULT_SCHEDULED = "fault_scheduled"
    """A fault will be injected (:mod:`mufusion.sim.faults`)."""
    ESTIMATE_FALLBACK = "estimate_fallback"
    """The estimate was unusable: the last valid one or the floor replaced it."""
    FRICTION_SOURCE_ERROR = "friction_source_error"
    PLANNER_ERROR = "planner_error"
    CONTROLLER_ERROR = "controller_error"
    LOOP_ERROR = "loop_error"
    """An exception ended the run early (the log is kept)."""
    MINIMAL_RISK = "minimal_risk"
    """The minimal-risk manoeuvre started (latched to the end of the run)."""
    PROBE_START = "probe_start"
    PROBE_END = "probe_end"
    LANE_RECOVERY = "lane_recovery"
    """μ̂ was relaxed towards the posterior mean to keep the lane, or that did not help."""
    FUTILE_EVASION = "futile_evasion"
    """Every evasion hits the obstacle: braking in lane instead."""
    EVASION_AT_UPPER_EDGE = "evasion_at_upper_edge"
    """Every evasion up to the estimates' central value hits the obstacle and one at the
    posterior's upper 95 % edge passes it: that one is driven."""
    EVASION_AT_TIRES_LIMIT = "evasion_at_tires_limit"
    """Without a posterior: every evasion with μ̂ hits the obstacle and one at the tires' limit
    (μ̂ / λ) passes it: that one is driven."""
    GRAZE_OVER_STOP = "graze_over_stop"
    """Every evasion hits the obstacle, but braking in lane would meet it wider: the evasion
    with the most friction is driven (docs/decisions/0126)."""
    STOP_PROBE = "stop_probe"
    """A braking probe for a stop in lane started."""
    STOP_PROBE_END = "stop_probe_end"
    UNSEEN_ROAD_IGNORED = "unseen_road_ignored"
    """The friction source declares the road beyond its grid (``unseen_mu``) and the planner's
    ``step`` takes no ``unseen_road``: its speeds cannot use it (logged once per run)."""


ERROR_EVENTS: tuple[EventKind, ...] = (
    EventKind.FRICTION_SOURCE_ERROR, EventKind.PLANNER_ERROR, EventKind.CONTROLLER_ERROR,
    EventKind.LOOP_ERROR,
)
"""The kinds that report an exception inside the loop."""

EventSink = Callable[[float, EventKind, str], None]
"""Where a supervisor reports an event: ``sink(t_s, kind, detail)`` (the recorder's ``event``)."""
