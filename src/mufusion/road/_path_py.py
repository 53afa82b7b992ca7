"""The reference path's frame and Newton projection for one point, in plain floats.

The pure-Python twins of the compiled ``mufusion.road._path_c`` (bit for bit the same values);
:class:`~mufusion.road.path.ReferencePath` binds them as its ``_frame_python`` and
``_newton_python`` methods, so ``self`` is the path (typed ``Any`` here: importing the class
would make an import cycle).
"""

from __future__ import annotations

import math
from bisect import bisect_right as _bisect_right
from typing import Any


def frame_python(self: Any, s: float) -> tuple[float, float, float, float]:
    """Plain-float version of :meth:`_frame` for one point."""
    # min(max(s, 0), length) and min(max(j, 0), last) as comparisons (the same values,
    # NaN and signed zeros included, without the built-in calls).
    clamped = 0.0 if 0.0 > s else s
    length = self.length_m
    if length < clamped:
        clamped = length
    j = _bisect_right(self._py_anchor_s, clamped) - 1
    j = self._py_last_anchor if self._py_last_anchor < j else (0 if 0 > j else j)
    a, x, y, start, k0, dk, psi0 = self._py_anchors[j]
    sigma = clamped - start
    heading = psi0 + k0 * sigma + 0.5 * dk * sigma * sigma
    if dk == 0.0:
        # Straight or arc: the quadrature's integral in closed form, the chord from the
        # anchor, 2 sin(κΔ/2)/κ long, along the heading at the midpoint (equal to the
        # 8-point rule to rounding).
        delta = clamped - a
        half_turn = 0.5 * k0 * delta
        chord = delta if half_turn == 0.0 else delta * math.sin(half_turn) / half_turn
        mid_heading = heading - half_turn
        x += chord * math.cos(mid_heading)
        y += chord * math.sin(mid_heading)
    else:
        half, mid = 0.5 * (clamped - a), 0.5 * (clamped + a)
        for node, weight in self._py_gauss:
            sigma_node = mid + half * node - start
            psi = psi0 + k0 * sigma_node + 0.5 * dk * sigma_node * sigma_node
            x += half * weight * math.cos(psi)
            y += half * weight * math.sin(psi)
    if s == clamped:
        return x, y, heading, k0 + dk * sigma
    beyond = s - clamped
    return x + beyond * math.cos(heading), y + beyond * math.sin(heading), heading, 0.0

def newton_python(
    self: Any, px: float, py: float, s: float, max_iterations: int
) -> tuple[float, float, float, bool]:
    """Foot point of ``(px, py)`` by Newton from ``s``: ``(s, d, heading, converged)``."""
    frame, cos, sin = self._frame_python, math.cos, math.sin
    for _ in range(max_iterations):
        cx, cy, heading, kappa = frame(s)
        tx, ty = cos(heading), sin(heading)
        ex, ey = px - cx, py - cy
        d = -ex * ty + ey * tx
        # Foot point condition (P − C(s))·t(s) = 0; its derivative is −(1 − κ d), floored
        # at 0.1 (max(·, 0.1) as a comparison).
        slope = 1.0 - kappa * d
        step = (ex * tx + ey * ty) / (0.1 if 0.1 > slope else slope)
        s += step
        if abs(step) < 1e-9:
            # At the converged foot point, a step this short moves d by O(κ·step²) (below
            # rounding) and turns the heading by κ·step: no need to evaluate the frame again.
            return s, d, heading + kappa * step, True
    cx, cy, heading, _ = frame(s)
    return s, -(px - cx) * math.sin(heading) + (py - cy) * math.cos(heading), heading, False
