"""Closed loop: plant, controller interface, planner and estimators at their own rates; run log."""

from mufusion.sim.log import RunLog, load_run

__all__ = ["RunLog", "load_run"]
