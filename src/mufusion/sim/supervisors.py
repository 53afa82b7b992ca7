"""One run's supervisors, in the order they act, and its minimal-risk manoeuvre."""

from __future__ import annotations

from dataclasses import dataclass

from mufusion.sim.lane_recovery import LaneRecovery
from mufusion.sim.minimal_risk import MinimalRisk
from mufusion.sim.probing import Probing
from mufusion.sim.stop_in_lane import StopInLane
from mufusion.sim.supervisor import Supervisor


@dataclass(frozen=True)
class Supervision:
    """One run's supervisors and its minimal-risk manoeuvre (each holds what it did)."""

    stop_in_lane: StopInLane
    lane_recovery: LaneRecovery
    probing: Probing
    minimal_risk: MinimalRisk

    @property
    def in_order(self) -> tuple[Supervisor, ...]:
        """The supervisors in the order they act: the stop in lane overrides the rule's evasion,
        lane recovery re-plans, and a probe is considered with the estimate the step plans with."""
        return (self.stop_in_lane, self.lane_recovery, self.probing)
