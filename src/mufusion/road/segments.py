"""The pieces a reference path is built from: :class:`PathSegment` (straight, arc, clothoid)."""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["PathSegment"]


@dataclass(frozen=True)
class PathSegment:
    """One centreline piece whose curvature varies linearly from start to end.

    Attributes
    ----------
    length_m
        Arc length [m], > 0.
    curvature_start_1pm, curvature_end_1pm
        Curvature at the start and the end [1/m]; left turns positive.
    """

    length_m: float
    curvature_start_1pm: float = 0.0
    curvature_end_1pm: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.length_m) and self.length_m > 0.0):
            raise ValueError(f"PathSegment.length_m must be finite and > 0, got {self.length_m!r}")
        for name in ("curvature_start_1pm", "curvature_end_1pm"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"PathSegment.{name} must be finite, got {getattr(self, name)!r}")

    @classmethod
    def straight(cls, length_m: float) -> PathSegment:
        """A straight of ``length_m`` [m]."""
        return cls(length_m, 0.0, 0.0)

    @classmethod
    def arc(cls, radius_m: float, angle_rad: float) -> PathSegment:
        """A circular arc of ``radius_m`` [m] turning by ``angle_rad`` (> 0 left, < 0 right)."""
        if not (radius_m > 0.0 and math.isfinite(radius_m)):
            raise ValueError(f"radius_m must be finite and > 0, got {radius_m!r}")
        curvature = math.copysign(1.0 / radius_m, angle_rad)
        return cls(abs(angle_rad) * radius_m, curvature, curvature)

    @classmethod
    def clothoid(cls, length_m: float, curvature_start_1pm: float, curvature_end_1pm: float):
        """A clothoid (curvature linear in s) of ``length_m`` [m]."""
        return cls(length_m, curvature_start_1pm, curvature_end_1pm)
