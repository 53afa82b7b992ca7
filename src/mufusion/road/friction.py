"""True road friction: piecewise-constant segments over the progress s, optionally per lane."""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

DEFAULT_LANE_WIDTH_M = 3.5


def _check_mu_values(name: str, values: Sequence[float]) -> None:
    for value in values:
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"FrictionMap.{name} values must be finite and > 0, got {value!r}")


@dataclass(frozen=True)
class FrictionMap:
    """Road friction coefficient μ as piecewise-constant segments over s.

    Segment ``i`` covers ``start_s_m[i] ≤ s < start_s_m[i + 1]``; the first value also holds
    before ``start_s_m[0]`` and the last one to infinity.

    Attributes
    ----------
    start_s_m
        Increasing segment starts [m].
    mu
        μ of the ego lane (and of the whole road if ``mu_opposing`` is None) per segment [-].
    mu_opposing
        Optional μ of the opposing lane per segment (``d > lane_width_m / 2``) [-].
    lane_width_m
        Lane width [m] that separates the lanes for ``mu_opposing``.

    Raises
    ------
    ValueError
        If lengths differ, starts do not increase, or any μ is not > 0.

    Examples
    --------
    >>> FrictionMap.step(0.8, 0.4, 55.0).mu_at(np.array([0.0, 60.0])).tolist()
    [0.8, 0.4]
    """

    start_s_m: tuple[float, ...]
    mu: tuple[float, ...]
    mu_opposing: tuple[float, ...] | None = None
    lane_width_m: float = DEFAULT_LANE_WIDTH_M

    def __post_init__(self) -> None:
        object.__setattr__(self, "start_s_m", tuple(float(v) for v in self.start_s_m))
        object.__setattr__(self, "mu", tuple(float(v) for v in self.mu))
        if len(self.start_s_m) == 0 or len(self.mu) != len(self.start_s_m):
            raise ValueError(
                "FrictionMap.start_s_m and FrictionMap.mu must be non-empty and of equal length, "
                f"got {len(self.start_s_m)} and {len(self.mu)}"
            )
        if np.any(np.diff(self.start_s_m) <= 0.0) or not np.all(np.isfinite(self.start_s_m)):
            raise ValueError(f"FrictionMap.start_s_m must be finite and increasing, "
                             f"got {self.start_s_m}")
        _check_mu_values("mu", self.mu)
        if self.mu_opposing is not None:
            object.__setattr__(self, "mu_opposing", tuple(float(v) for v in self.mu_opposing))
            if len(self.mu_opposing) != len(self.start_s_m):
                raise ValueError("FrictionMap.mu_opposing must have one value per segment")
            _check_mu_values("mu_opposing", self.mu_opposing)
        if not (math.isfinite(self.lane_width_m) and self.lane_width_m > 0.0):
            raise ValueError(f"FrictionMap.lane_width_m must be > 0, got {self.lane_width_m!r}")

    @classmethod
    def uniform(cls, mu: float) -> FrictionMap:
        """The same μ everywhere."""
        return cls((0.0,), (mu,))

    @classmethod
    def step(cls, mu_before: float, mu_after: float, change_s_m: float) -> FrictionMap:
        """``mu_before`` up to ``change_s_m`` [m], ``mu_after`` from there on."""
        # The first segment's value also holds before its start, so any start before works.
        return cls((change_s_m - 1.0, change_s_m), (mu_before, mu_after))

    def mu_at(self, s_m: np.ndarray | float, d_m: np.ndarray | float | None = None) -> np.ndarray:
        """True μ at progress ``s_m`` [m] and, if per-lane values exist, lateral offset ``d_m``.

        Parameters
        ----------
        s_m
            Progress [m], any shape.
        d_m
            Lateral offset [m] (left +), broadcast with ``s_m``; ignored without ``mu_opposing``.

        Returns
        -------
        ndarray
            μ, the broadcast shape of the arguments.
        """
        s = np.asarray(s_m, dtype=float)
        # np.minimum/np.maximum: np.clip's result at a fraction of its per-call overhead.
        index = np.minimum(
            np.maximum(np.searchsorted(self.start_s_m, s, side="right") - 1, 0), len(self.mu) - 1
        )
        ego = np.asarray(self.mu)[index]
        if self.mu_opposing is None or d_m is None:
            return ego
        d = np.asarray(d_m, dtype=float)
        opposing = np.asarray(self.mu_opposing)[index]
        return np.where(d > 0.5 * self.lane_width_m, opposing, ego)

    def mu_at_point(self, s_m: float, d_m: float | None = None) -> float:
        """:meth:`mu_at` for one point, in plain floats (the closed loop's per-step look-up).

        Examples
        --------
        >>> FrictionMap.step(0.8, 0.4, 55.0).mu_at_point(60.0)
        0.4
        """
        index = min(max(bisect.bisect_right(self.start_s_m, s_m) - 1, 0), len(self.mu) - 1)
        if self.mu_opposing is not None and d_m is not None and d_m > 0.5 * self.lane_width_m:
            return self.mu_opposing[index]
        return self.mu[index]
