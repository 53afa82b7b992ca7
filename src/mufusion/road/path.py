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

import functools
import math
from bisect import bisect_right as _bisect_right
from collections.abc import Callable, Sequence

import numpy as np

from mufusion.road._path_py import frame_python, newton_python
from mufusion.road.segments import PathSegment

_ANCHOR_SPACING_M = 2.0
# Up to this many points, to_frenet loops over plain floats (faster than numpy for few points).
_SCALAR_PATH_MAX_POINTS = 8
_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(8)
# Warm-started projection (to_frenet_point): Newton iterations before the global search takes
# over, and the largest accepted distance from the guess [m].
_WARM_START_ITERATIONS = 8
_WARM_START_MAX_JUMP_M = 5.0


@functools.lru_cache(maxsize=1)
def compiled_frames_available() -> bool:
    """Whether the install built the compiled frame and projection (``road/_path_c.pyx``;
    ``pip install`` compiles it, a bare source tree has only the Python)."""
    try:
        from mufusion.road._path_c import CompiledFrames  # noqa: F401
    except ImportError:
        return False
    return True


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
        # No curvature anywhere (+0.0 at every start, no change): κ(s) is +0.0 for every s, which
        # is what the general expression gives (+0.0 + 0.0·σ), without its dozen array calls.
        self._flat = not (np.any(self._k0) or np.any(self._dk) or np.any(np.signbit(self._k0)))
        headings = [float(start_heading_rad)]
        for k0, dk, length in zip(self._k0, self._dk, lengths, strict=True):
            headings.append(headings[-1] + k0 * length + 0.5 * dk * length**2)
        self._psi0 = np.array(headings)
        self._max_abs_curvature = float(
            max(np.max(np.abs(self._k0)), np.max(np.abs(self._k0 + self._dk * lengths)))
        )
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
        self._table_heading = self.heading(table)
        # Plain-float copies for the scalar path used by the control loop (one pose at a time,
        # where numpy's per-call overhead would dominate): per anchor, its s, position and the
        # coefficients of its segment (an anchor never lies in a later segment than the points
        # it serves, so one search finds both).
        anchor_segment = self._segment_index(self._anchor_s).tolist()
        self._py_anchor_s = self._anchor_s.tolist()
        self._py_last_anchor = len(self._py_anchor_s) - 2
        self._py_anchors = [
            (a, x, y, float(self._seg_start[i]), float(self._k0[i]), float(self._dk[i]),
             float(self._psi0[i]))
            for a, (x, y), i in zip(self._py_anchor_s, self._anchor_xy.tolist(), anchor_segment,
                                    strict=True)
        ]
        self._py_gauss = list(zip(_GL_NODES.tolist(), _GL_WEIGHTS.tolist(), strict=True))
        # The per-step frame and Newton projection: the compiled twin where the install built
        # it (the same values, bit for bit; see road/_path_c.pyx), else the Python below.
        self._frame_scalar: Callable[[float], tuple[float, float, float, float]]
        self._newton_scalar: Callable[[float, float, float, int],
                                      tuple[float, float, float, bool]]
        if compiled_frames_available():
            from mufusion.road._path_c import CompiledFrames

            frames = CompiledFrames(self._py_anchors, self._py_gauss, self.length_m)
            self._frame_scalar, self._newton_scalar = frames.frame, frames.newton
        else:
            self._frame_scalar, self._newton_scalar = self._frame_python, self._newton_python

    @property
    def max_abs_curvature_1pm(self) -> float:
        """Largest |κ| along the path [1/m] (0 for a straight)."""
        return self._max_abs_curvature

    # --- curvature and heading: closed form per segment -------------------------------------
    def _segment_index(self, s: np.ndarray) -> np.ndarray:
        index = np.searchsorted(self._seg_start, s, side="right") - 1
        # np.minimum/np.maximum: much cheaper than np.clip on the small arrays of the control loop.
        return np.maximum(np.minimum(index, len(self.segments) - 1), 0)

    def curvature(self, s_m: np.ndarray | float) -> np.ndarray:
        """Path curvature κ(s) [1/m], left positive; 0 on the straight extensions."""
        s = np.asarray(s_m, dtype=float)
        if self._flat:
            return np.zeros(s.shape)
        i = self._segment_index(s)
        sigma = s - self._seg_start[i]
        inside = (s >= 0.0) & (s <= self.length_m)
        return np.where(inside, self._k0[i] + self._dk[i] * sigma, 0.0)

    def curvature_at(self, s_m: float) -> float:
        """:meth:`curvature` at one progress [m], in plain floats.

        Examples
        --------
        >>> path = ReferencePath([PathSegment.straight(10.0), PathSegment.arc(20.0, 1.0)])
        >>> path.curvature_at(5.0), path.curvature_at(15.0), path.curvature_at(-1.0)
        (0.0, 0.05, 0.0)
        """
        if not 0.0 <= s_m <= self.length_m:
            return 0.0
        j = min(max(_bisect_right(self._py_anchor_s, s_m) - 1, 0),
                len(self._py_anchor_s) - 2)
        _, _, _, start, k0, dk, _ = self._py_anchors[j]
        return k0 + dk * (s_m - start)

    def heading(self, s_m: np.ndarray | float) -> np.ndarray:
        """Path heading ψ_path(s) [rad] (continuous, not wrapped)."""
        s = np.asarray(s_m, dtype=float)
        clamped = np.maximum(np.minimum(s, self.length_m), 0.0)
        i = self._segment_index(clamped)
        sigma = clamped - self._seg_start[i]
        return self._psi0[i] + self._k0[i] * sigma + 0.5 * self._dk[i] * sigma**2

    def _integrate(
        self, a: np.ndarray, b: np.ndarray, segment: np.ndarray | None = None
    ) -> np.ndarray:
        """∫_a^b (cos ψ, sin ψ) ds for a, b inside one segment; returns shape (2, n)."""
        half = 0.5 * (b - a)
        nodes = 0.5 * (a + b)[:, None] + half[:, None] * _GL_NODES[None, :]
        i = (self._segment_index(0.5 * (a + b)) if segment is None else segment)[:, None]
        sigma = nodes - self._seg_start[i]
        psi = self._psi0[i] + self._k0[i] * sigma + 0.5 * self._dk[i] * sigma**2
        return np.stack(
            [half * (np.cos(psi) @ _GL_WEIGHTS), half * (np.sin(psi) @ _GL_WEIGHTS)]
        )

    def _frame(self, s: np.ndarray) -> tuple[np.ndarray, ...]:
        """x, y, heading and curvature at 1-D ``s`` with one segment lookup (Newton loop)."""
        clamped = np.maximum(np.minimum(s, self.length_m), 0.0)
        i = self._segment_index(clamped)
        j = np.maximum(
            np.minimum(np.searchsorted(self._anchor_s, clamped, side="right") - 1,
                       self._anchor_s.size - 2), 0
        )
        # An anchor never lies in a later segment than the point it serves.
        xy = self._anchor_xy[j].T + self._integrate(self._anchor_s[j], clamped, i)
        sigma = clamped - self._seg_start[i]
        heading = self._psi0[i] + self._k0[i] * sigma + 0.5 * self._dk[i] * sigma**2
        beyond = s - clamped
        inside = beyond == 0.0
        kappa = np.where(inside, self._k0[i] + self._dk[i] * sigma, 0.0)
        xy[0] += beyond * np.cos(heading)
        xy[1] += beyond * np.sin(heading)
        return xy[0], xy[1], heading, kappa

    # The per-point frame and Newton projection in plain floats (mufusion.road._path_py), the
    # twins of the compiled _path_c's.
    _frame_python = frame_python
    _newton_python = newton_python

    def _to_frenet_scalar(self, px: float, py: float) -> tuple[float, float, float]:
        """Global projection of one point: nearest 0.5 m table entry, then Newton."""
        k = int(np.argmin((self._table_xy[:, 0] - px) ** 2 + (self._table_xy[:, 1] - py) ** 2))
        heading = float(self._table_heading[k])
        table_x, table_y = self._table_xy[k].tolist()
        s = float(self._table_s[k]) + (px - table_x) * math.cos(heading) + (
            py - table_y
        ) * math.sin(heading)
        s, d, heading, _ = self._newton_scalar(px, py, s, 30)
        return s, d, heading

    def to_frenet_point(
        self, x_m: float, y_m: float, psi_rad: float = 0.0, s_guess_m: float | None = None
    ) -> tuple[float, float, float]:
        """One Cartesian pose → Frenet pose in plain floats, optionally warm-started.

        The same projection as :meth:`to_frenet` (equal to rounding), without numpy's per-call
        overhead. With ``s_guess_m`` (e.g. the point's foot point one time step earlier) Newton
        starts there instead of at the nearest table entry; its result is kept only if it
        converges within a few iterations, no more than 5 m from the guess and closer to the path
        than half its smallest radius of curvature (where the foot point is unique, for paths that
        do not come back near themselves); otherwise the global search answers.

        Parameters
        ----------
        x_m, y_m, psi_rad
            Cartesian position [m] and heading [rad].
        s_guess_m
            Start of the local search [m], or None for the global search.

        Returns
        -------
        s, d, dpsi
            Progress [m], lateral offset [m] (left +), heading error wrapped to (−π, π] [rad].

        Examples
        --------
        >>> path = ReferencePath([PathSegment.straight(50.0)])
        >>> s, d, dpsi = path.to_frenet_point(20.0, 1.5, 0.1, s_guess_m=19.0)
        >>> round(s, 12), round(d, 12), round(dpsi, 12)
        (20.0, 1.5, 0.1)
        """
        px, py = float(x_m), float(y_m)
        if s_guess_m is not None:
            s, d, heading, converged = self._newton_scalar(
                px, py, float(s_guess_m), _WARM_START_ITERATIONS
            )
            if not (
                converged
                and abs(s - s_guess_m) <= _WARM_START_MAX_JUMP_M
                and abs(d) * self._max_abs_curvature <= 0.5
            ):
                s, d, heading = self._to_frenet_scalar(px, py)
        else:
            s, d, heading = self._to_frenet_scalar(px, py)
        error = float(psi_rad) - heading
        return s, d, math.atan2(math.sin(error), math.cos(error))

    def position(self, s_m: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """Cartesian centreline point at progress ``s_m`` [m]; returns ``(x, y)`` arrays."""
        s = np.asarray(s_m, dtype=float)
        x, y, _, _ = self._frame(s.reshape(-1))
        return x.reshape(s.shape), y.reshape(s.shape)

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
        # _frame's heading is heading(s): the same clamping, segment and expression.
        x, y, psi_path, _ = (v.reshape(s.shape) for v in self._frame(s.reshape(-1)))
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
        if px.size <= _SCALAR_PATH_MAX_POINTS:
            pairs = [self._to_frenet_scalar(a, b) for a, b in zip(px.tolist(), py.tolist(),
                                                                 strict=True)]
            s = np.array([p[0] for p in pairs])
            d = np.array([p[1] for p in pairs])
            heading = np.array([p[2] for p in pairs])
            dpsi = np.angle(np.exp(1j * (psi.reshape(-1) - heading)))
            return s.reshape(shape), d.reshape(shape), dpsi.reshape(shape)
        nearest = np.empty(px.size, dtype=int)
        chunk = 2048
        for start in range(0, px.size, chunk):
            dx = px[start : start + chunk, None] - self._table_xy[None, :, 0]
            dy = py[start : start + chunk, None] - self._table_xy[None, :, 1]
            nearest[start : start + chunk] = np.argmin(dx * dx + dy * dy, axis=1)
        s = self._table_s[nearest]
        for _ in range(30):
            cx, cy, heading, kappa = self._frame(s)
            tx, ty = np.cos(heading), np.sin(heading)
            ex, ey = px - cx, py - cy
            along = ex * tx + ey * ty
            d = -ex * ty + ey * tx
            # Foot point condition (P − C(s))·t(s) = 0; its derivative is −(1 − κ d).
            step = along / np.maximum(1.0 - kappa * d, 0.1)
            s = s + step
            if np.all(np.abs(step) < 1e-9):
                break
        # One more evaluation at the converged foot point (the last step was < 1e-9 m).
        cx, cy, heading, _ = self._frame(s)
        d = -(px - cx) * np.sin(heading) + (py - cy) * np.cos(heading)
        dpsi = np.angle(np.exp(1j * (psi.reshape(-1) - heading)))
        return s.reshape(shape), d.reshape(shape), dpsi.reshape(shape)
