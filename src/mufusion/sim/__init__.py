"""Closed loop: plant, controller interface, planner and estimators at their own rates; run log."""

from __future__ import annotations

from typing import TYPE_CHECKING

from mufusion._lazy import lazy_getattr

if TYPE_CHECKING:
    from mufusion.sim.log import RunLog, load_run

__all__ = ["RunLog", "load_run"]

# The run log (and pandas with it) loads on first use: the scenario schema imports this package's
# settings, and a command refused for bad input must not wait for pandas.
__getattr__ = lazy_getattr(__name__, {"RunLog": "log", "load_run": "log"})
