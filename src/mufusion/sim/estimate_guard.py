"""What the planner gets when the friction estimate is missing, invalid, delayed or stale.

The rule (also in :class:`~mufusion.sim.loop.ClosedLoop`'s notes): an estimate must be finite and
at most ``SafetySettings.max_estimate_age_s`` old. Otherwise the last estimate that was, re-sampled
at the absolute positions it was made for, is used while it is young enough; else
``SafetySettings.mu_floor`` over the whole horizon. Every substitution is an event.
"""

from __future__ import annotations

import dataclasses
from collections import deque
from dataclasses import dataclass

import numpy as np

from mufusion.configurations import FrictionEstimate
from mufusion.planner.safety import SafetySettings
from mufusion.sim.events import EventKind, EventSink

Source = str
"""``current``, ``delayed`` (an injected delay within the age limit), ``last_valid`` or
``floor``."""


@dataclass(frozen=True)
class Anchored:
    """A friction estimate and where and when it was made."""

    t_s: float
    s_m: float
    estimate: FrictionEstimate

    @property
    def finite(self) -> bool:
        return bool(np.all(np.isfinite(np.asarray(self.estimate.mu_hat, dtype=float))))


class EstimateGuard:
    """Keeps the recent estimates and hands the planner a usable one.

    Parameters
    ----------
    grid_m
        Distances ahead of the estimates [m].
    safety
        Age limit and friction floor.
    event
        Called with ``(t_s, kind, detail)`` for every substitution.
    """

    def __init__(
        self,
        grid_m: np.ndarray,
        safety: SafetySettings,
        event: EventSink,
    ) -> None:
        self.grid_m = np.asarray(grid_m, dtype=float)
        self.safety = safety
        self._event = event
        self._history: deque[Anchored] = deque(maxlen=64)
        self._last_valid: Anchored | None = None

    def usable(
        self,
        t_s: float,
        s_ego_m: float,
        fresh: FrictionEstimate | None,
        *,
        delay_s: float = 0.0,
        corrupt: bool = False,
    ) -> tuple[FrictionEstimate, Source, float]:
        """The estimate for the planning step at ``t_s``, where it came from and its age [s].

        ``fresh`` is this step's estimate (None if the source failed); ``delay_s`` > 0 hands the
        planner the one made that long ago instead (an injected delay); ``corrupt`` replaces its
        values by NaN (an injected fault).
        """
        if fresh is not None:
            self._history.append(Anchored(t_s, s_ego_m, fresh))
        candidate = None if fresh is None else Anchored(t_s, s_ego_m, fresh)
        source: Source = "current"
        if delay_s > 0.0 and self._history:
            older = [a for a in self._history if a.t_s <= t_s - delay_s + 1e-9]
            candidate, source = (older[-1] if older else self._history[0]), "delayed"
        if candidate is not None and corrupt:
            nan = np.full(np.shape(candidate.estimate.mu_hat), np.nan)
            candidate = dataclasses.replace(
                candidate, estimate=dataclasses.replace(candidate.estimate, mu_hat=nan)
            )
        max_age = self.safety.max_estimate_age_s
        if candidate is not None and candidate.finite and t_s - candidate.t_s <= max_age + 1e-9:
            if source == "current":
                self._last_valid = candidate
                return candidate.estimate, source, 0.0
            return self.on_grid(candidate, s_ego_m), source, t_s - candidate.t_s
        why = "missing" if candidate is None else (
            "not finite" if not candidate.finite else f"{t_s - candidate.t_s:.2f} s old"
        )
        last = self._last_valid
        if last is not None and t_s - last.t_s <= max_age + 1e-9:
            self._event(t_s, EventKind.ESTIMATE_FALLBACK, f"estimate {why}: last valid one used")
            return self.on_grid(last, s_ego_m), "last_valid", t_s - last.t_s
        self._event(t_s, EventKind.ESTIMATE_FALLBACK,
                    f"estimate {why}: μ = {self.safety.mu_floor} assumed")
        local = fresh if fresh is not None else (last.estimate if last is not None else None)
        floor = FrictionEstimate(
            s_m=self.grid_m,
            mu_hat=np.full(self.grid_m.size, self.safety.mu_floor),
            local_available=bool(local and local.local_available),
            local_mu=None if local is None else local.local_mu,
        )
        return floor, "floor", np.inf if last is None else t_s - last.t_s

    def on_grid(self, anchored: Anchored, s_ego_m: float) -> FrictionEstimate:
        """An older estimate re-sampled on the grid ahead of ``s_ego_m`` (by absolute s)."""
        mu_hat = np.interp(
            s_ego_m + self.grid_m, anchored.s_m + self.grid_m,
            np.asarray(anchored.estimate.mu_hat, dtype=float),
        )
        return dataclasses.replace(
            anchored.estimate, s_m=self.grid_m, mu_hat=mu_hat, fused=None, data=None
        )
