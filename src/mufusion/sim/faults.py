"""Faults injected into the closed loop (the reactions' settings: :class:`SafetySettings`).

A :class:`Fault` is active on ``[start_s, start_s + duration_s)`` of simulated time. What each kind
does (the loop applies it; :mod:`mufusion.sim.loop` documents the reactions):

``local_dropout``
    the slip-based estimator gets no excitation signal: it cannot measure and holds its value.
``camera_dropout``
    the camera reports nothing (no predictive data).
``camera_nan``
    the camera reports NaN values: corrupt data that must be detected and discarded.
``estimate_delay``
    the planner receives the friction estimate made ``delay_s`` earlier (a stale estimate).
``estimate_nan``
    the friction estimate handed to the planner is NaN over the horizon.
``solver_failure``
    the planner fails (as if its solver returned an error) at every planning step.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, get_args

from mufusion.planner.safety import SafetySettings

__all__ = ["FAULT_KINDS", "Fault", "FaultKind", "SafetySettings", "active_kinds",
           "estimate_delay_s"]

FaultKind = Literal[
    "local_dropout", "camera_dropout", "camera_nan", "estimate_delay", "estimate_nan",
    "solver_failure",
]
FAULT_KINDS: tuple[str, ...] = get_args(FaultKind)


@dataclass(frozen=True)
class Fault:
    """One injected fault.

    Raises
    ------
    ValueError
        If ``kind`` is unknown, a time is negative or not finite, or ``delay_s`` is given for a
        kind other than ``estimate_delay`` (or missing for it).
    """

    kind: FaultKind
    start_s: float
    duration_s: float
    delay_s: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in FAULT_KINDS:
            raise ValueError(f"kind must be one of {list(FAULT_KINDS)}, got {self.kind!r}")
        for name in ("start_s", "duration_s", "delay_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{name} must be finite and >= 0 s, got {value!r}")
        if (self.kind == "estimate_delay") != (self.delay_s > 0.0):
            raise ValueError("delay_s must be > 0 for kind 'estimate_delay' and absent otherwise")

    def active(self, t_s: float) -> bool:
        return self.start_s <= t_s < self.start_s + self.duration_s

    def describe(self) -> str:
        """The fault in words (the log's ``fault_scheduled`` event)."""
        text = f"{self.kind} from {self.start_s:g} s for {self.duration_s:g} s"
        return text + (f", delay {self.delay_s:g} s" if self.delay_s else "")


def active_kinds(faults: Sequence[Fault], t_s: float) -> frozenset[str]:
    """The kinds of the faults active at ``t_s``."""
    return frozenset(f.kind for f in faults if f.active(t_s))


def estimate_delay_s(faults: Sequence[Fault], t_s: float) -> float:
    """The largest injected estimate delay at ``t_s`` [s] (0 when none is active)."""
    return max((f.delay_s for f in faults if f.kind == "estimate_delay" and f.active(t_s)),
               default=0.0)
