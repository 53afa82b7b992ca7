"""What one step of lane recovery did, as the loop reports it (:mod:`.lane_recovery`)."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum


class RecoveryOutcome(StrEnum):
    """What one step of lane recovery did (each is a ``lane_recovery`` event but ``BRAKING``, a
    ``futile_evasion`` one)."""

    RELAXED = "relaxed"
    """A plan with μ̂ relaxed was adopted."""
    DID_NOT_HELP = "did_not_help"
    """No relaxation did better: the friction-limited plan was kept."""
    EASED = "eased"
    """The lane is kept with one step less of the held relaxation, which is adopted."""
    BRAKING = "braking"
    """Every evasion hits the obstacle: the stop in lane is adopted."""
    UPPER_EDGE = "upper_edge"
    """Every candidate hits the obstacle and the evasion at the posterior's upper 95 % edge
    passes it: that one is adopted (an ``evasion_at_upper_edge`` event)."""
    TIRES_LIMIT = "tires_limit"
    """Without a posterior: every evasion with μ̂ hits the obstacle and the one at the tires'
    limit passes it: that one is adopted (an ``evasion_at_tires_limit`` event)."""
    GRAZE = "graze"
    """Every evasion hits the obstacle, the one with the most friction narrower than the stop in
    lane would: that one is adopted (a ``graze_over_stop`` event)."""


@dataclass(frozen=True)
class Recovery:
    """One step of lane recovery that was reported."""

    t_s: float
    outcome: RecoveryOutcome
    alpha: float
    """The relaxation adopted (0: none)."""
    held_alpha: float
    """The relaxation held from the step before."""
