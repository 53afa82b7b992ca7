"""Reference path from a centreline of straights, circular arcs and clothoids, with exact Frenet ↔
Cartesian conversion.

Frenet frame (road-aligned): progress ``s`` along the path [m], lateral offset ``d`` [m] (left of
the path positive), heading error ``Δψ = ψ − ψ_path(s)`` [rad]. The curvature of every segment is
linear in ``s`` (straights and arcs are the constant case), so the path heading is a quadratic in
``s`` and positions are integrals of ``(cos ψ, sin ψ)``; they are evaluated by 8-point
Gauss–Legendre quadrature from anchor points at most 2 m apart, i.e. to machine precision.
Outside ``[0, length]`` the path continues as straight lines along its end headings, so a vehicle
that overshoots still has well-defined Frenet coordinates.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

_ANCHOR_SPACING_M = 2.0
_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(8)


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


class ReferencePath:
    """A centreline built from :class:`PathSegment` pieces, with Frenet ↔ Cartesian conversion.

    Parameters
    ----------
    segments
        The pieces in driving order (at least one).
    start_xy_m
        Cartesian position of ``s = 0`` [m].
    start_heading_rad
        Path heading at ``s = 0`` [rad], counter-clockwise from the X axis.

    Raises
    ------
    ValueError
        If ``segments`` is empty.

    Examples
    --------
    >>> path = ReferencePath([PathSegment.straight(10.0), PathSegment.arc(10.0, math.pi / 2)])
    >>> x, y = path.position(np.array([10.0 + 5.0 * math.pi]))
    >>> round(float(x[0]), 9), round(float(y[0]), 9)
    (20.0, 10.0)
    """

    def __init__(
        self,
        segments: Sequence[PathSegment],
        start_xy_m: tuple[float, float] = (0.0, 0.0),
        start_heading_rad: float = 0.0,
    ) -> None:
        if len(segments) == 0:
            raise ValueError("segments must contain at least one PathSegment")
        self.segments = tuple(segments)
        lengths = np.array([seg.length_m for seg in self.segments])
        self._seg_start = np.concatenate([[0.0], np.cumsum(lengths)])
        self.length_m = float(self._seg_start[-1])
        self._k0 = np.array([seg.curvature_start_1pm for seg in self.segments])
        self._dk = np.array(
            [(seg.curvature_end_1pm - seg.curvature_start_1pm) / seg.length_m for seg in segments]
        )
        headings = [float(start_heading_rad)]
        for k0, dk, length in zip(self._k0, self._dk, lengths, strict=True):
            headings.append(headings[-1] + k0 * length + 0.5 * dk * length**2)
        self._psi0 = np.array(headings)
        # Anchors: every segment start plus subdivisions ≤ 2 m; positions by cumulative quadrature.
        anchors = [
            np.linspace(start, end, max(1, math.ceil((end - start) / _ANCHOR_SPACING_M)) + 1)[:-1]
            for start, end in zip(self._seg_start[:-1], self._seg_start[1:], strict=True)
        ]
        self._anchor_s = np.concatenate([*anchors, [self.length_m]])
        xy = np.zeros((self._anchor_s.size, 2))
        xy[0] = start_xy_m
        for i in range(1, self._anchor_s.size):
            step = self._integrate(self._anchor_s[i - 1 : i], self._anchor_s[i : i + 1])
            xy[i] = xy[i - 1] + step[:, 0]
        self._anchor_xy = xy
        self.start_xy_m = (float(start_xy_m[0]), float(start_xy_m[1]))
        self.start_heading_rad = float(start_heading_rad)
        self.end_xy_m = (float(xy[-1, 0]), float(xy[-1, 1]))
        self.end_heading_rad = float(self._psi0[-1])
        table = np.arange(-20.0, self.length_m + 20.0, 0.5)
        self._table_s = table
        self._table_xy = np.stack(self.position(table), axis=-1)

    # --- curvature and heading: closed form per segment -------------------------------------
    def _segment_index(self, s: np.ndarray) -> np.ndarray:
        index = np.searchsorted(self._seg_start, s, side="right") - 1
        return np.clip(index, 0, len(self.segments) - 1)

    def curvature(self, s_m: np.ndarray | float) -> np.ndarray:
        """Path curvature κ(s) [1/m], left positive; 0 on the straight extensions."""
        s = np.asarray(s_m, dtype=float)
        i = self._segment_index(s)
        sigma = s - self._seg_start[i]
        inside = (s >= 0.0) & (s <= self.length_m)
        return np.where(inside, self._k0[i] + self._dk[i] * sigma, 0.0)

    def heading(self, s_m: np.ndarray | float) -> np.ndarray:
        """Path heading ψ_path(s) [rad] (continuous, not wrapped)."""
        s = np.asarray(s_m, dtype=float)
        clamped = np.clip(s, 0.0, self.length_m)
        i = self._segment_index(clamped)
        sigma = clamped - self._seg_start[i]
        return self._psi0[i] + self._k0[i] * sigma + 0.5 * self._dk[i] * sigma**2

    def _integrate(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """∫_a^b (cos ψ, sin ψ) ds for a, b inside one segment; returns shape (2, n)."""
        half = 0.5 * (b - a)
        nodes = 0.5 * (a + b)[:, None] + half[:, None] * _GL_NODES[None, :]
        i = self._segment_index(0.5 * (a + b))[:, None]
        sigma = nodes - self._seg_start[i]
        psi = self._psi0[i] + self._k0[i] * sigma + 0.5 * self._dk[i] * sigma**2
        return np.stack(
            [half * (np.cos(psi) @ _GL_WEIGHTS), half * (np.sin(psi) @ _GL_WEIGHTS)]
        )

    def position(self, s_m: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """Cartesian centreline point at progress ``s_m`` [m]; returns ``(x, y)`` arrays."""
        s = np.asarray(s_m, dtype=float)
        flat = s.reshape(-1)
        clamped = np.clip(flat, 0.0, self.length_m)
        j = np.clip(np.searchsorted(self._anchor_s, clamped, side="right") - 1, 0,
                    self._anchor_s.size - 2)
        xy = self._anchor_xy[j].T + self._integrate(self._anchor_s[j], clamped)
        # Straight extensions beyond the ends.
        beyond = flat - clamped
        before, after = np.minimum(beyond, 0.0), np.maximum(beyond, 0.0)
        xy[0] += before * math.cos(self.start_heading_rad) + after * math.cos(self.end_heading_rad)
        xy[1] += before * math.sin(self.start_heading_rad) + after * math.sin(self.end_heading_rad)
        return xy[0].reshape(s.shape), xy[1].reshape(s.shape)

    # --- Frenet <-> Cartesian -------------------------------------------------------------------
    def to_cartesian(
        self,
        s_m: np.ndarray | float,
        d_m: np.ndarray | float,
        dpsi_rad: np.ndarray | float = 0.0,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Frenet pose → Cartesian pose (exact).

        Parameters
        ----------
        s_m, d_m, dpsi_rad
            Progress [m], lateral offset [m] (left +) and heading error [rad]; broadcast.

        Returns
        -------
        X, Y, psi
            Cartesian position [m] and heading [rad] (``ψ_path(s) + Δψ``, not wrapped).
        """
        s, d, dpsi = np.broadcast_arrays(
            np.asarray(s_m, float), np.asarray(d_m, float), np.asarray(dpsi_rad, float)
        )
        x, y = self.position(s)
        psi_path = self.heading(s)
        return x - d * np.sin(psi_path), y + d * np.cos(psi_path), psi_path + dpsi

    def to_frenet(
        self,
        x_m: np.ndarray | float,
        y_m: np.ndarray | float,
        psi_rad: np.ndarray | float = 0.0,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cartesian pose → Frenet pose by projection onto the path (Newton on the foot point).

        Valid for points closer to the path than its smallest radius of curvature (the foot
        point is then unique near the initial guess from a 0.5 m table).

        Parameters
        ----------
        x_m, y_m, psi_rad
            Cartesian position [m] and heading [rad]; broadcast.

        Returns
        -------
        s, d, dpsi
            Progress [m], lateral offset [m] (left +), heading error wrapped to (−π, π] [rad].
        """
        x, y, psi = np.broadcast_arrays(
            np.asarray(x_m, float), np.asarray(y_m, float), np.asarray(psi_rad, float)
        )
        shape = x.shape
        px, py = x.reshape(-1), y.reshape(-1)
        nearest = np.empty(px.size, dtype=int)
        chunk = 2048
        for start in range(0, px.size, chunk):
            dx = px[start : start + chunk, None] - self._table_xy[None, :, 0]
            dy = py[start : start + chunk, None] - self._table_xy[None, :, 1]
            nearest[start : start + chunk] = np.argmin(dx * dx + dy * dy, axis=1)
        s = self._table_s[nearest]
        for _ in range(30):
            cx, cy = self.position(s)
            heading = self.heading(s)
            tx, ty = np.cos(heading), np.sin(heading)
            ex, ey = px - cx, py - cy
            along = ex * tx + ey * ty
            across = -ex * ty + ey * tx
            # Foot point condition (P − C(s))·t(s) = 0; its derivative is −(1 − κ d).
            step = along / np.maximum(1.0 - self.curvature(s) * across, 0.1)
            s = s + step
            if np.all(np.abs(step) < 1e-11):
                break
        cx, cy = self.position(s)
        heading = self.heading(s)
        d = -(px - cx) * np.sin(heading) + (py - cy) * np.cos(heading)
        dpsi = np.angle(np.exp(1j * (psi.reshape(-1) - heading)))
        return s.reshape(shape), d.reshape(shape), dpsi.reshape(shape)
