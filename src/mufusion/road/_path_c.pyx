# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled twin of the reference path's plain-float frame and Newton projection (same values,
bit for bit).

:meth:`mufusion.road.path.ReferencePath._frame_python` and ``_newton_python`` run per plant step
for every tracked vehicle point; in Python most of their time is the interpreter's. Here the same
expressions run in C, in the same operand order (C and Python both evaluate ``a + b * c + d``
left to right, one IEEE-754 rounding per operation), with the C library's ``sin``/``cos``, which
are what Python's ``math`` module calls. The build turns off floating-point contraction (no fused
multiply-adds), so no operation is merged. NaN takes the same branches as in Python: every
comparison is written as it is there.
"""

from libc.math cimport cos, fabs, sin

import numpy as np


cdef class CompiledFrames:
    """The path's anchors and quadrature rule as C arrays.

    Parameters
    ----------
    anchors
        Per anchor ``(s, x, y, segment start, κ₀, dκ/ds, ψ₀)``, as the path's ``_py_anchors``.
    gauss
        ``(node, weight)`` pairs of the Gauss–Legendre rule on [−1, 1].
    length_m
        The path's length [m].
    """

    cdef double[::1] _s, _x, _y, _start, _k0, _dk, _psi0, _nodes, _weights
    cdef double _length
    cdef Py_ssize_t _count, _last, _n_gauss
    cdef object _args

    def __init__(self, list anchors, list gauss, double length_m):
        table = np.array(anchors, dtype=float).reshape(-1, 7)
        rule = np.array(gauss, dtype=float).reshape(-1, 2)
        if table.shape[0] < 2:
            raise ValueError("anchors must hold at least two anchors")
        self._s, self._x, self._y = [np.ascontiguousarray(c) for c in table.T[:3]]
        self._start, self._k0, self._dk, self._psi0 = [np.ascontiguousarray(c) for c in table.T[3:]]
        self._nodes, self._weights = [np.ascontiguousarray(c) for c in rule.T]
        self._length = length_m
        self._count = table.shape[0]
        self._last = self._count - 2
        self._n_gauss = rule.shape[0]
        self._args = (anchors, gauss, length_m)

    def __reduce__(self):
        return CompiledFrames, self._args

    cdef void _frame(self, double s, double* out) noexcept nogil:
        # ReferencePath._frame_python, statement for statement.
        cdef double clamped = 0.0 if 0.0 > s else s
        cdef double a, x, y, start, k0, dk, psi0, sigma, heading
        cdef double delta, half_turn, chord, mid_heading, half, mid, sigma_node, psi, beyond
        cdef Py_ssize_t lo = 0, hi = self._count, m, j, i
        if self._length < clamped:
            clamped = self._length
        while lo < hi:  # bisect.bisect_right
            m = (lo + hi) // 2
            if clamped < self._s[m]:
                hi = m
            else:
                lo = m + 1
        j = lo - 1
        j = self._last if self._last < j else (0 if 0 > j else j)
        a, x, y = self._s[j], self._x[j], self._y[j]
        start, k0, dk, psi0 = self._start[j], self._k0[j], self._dk[j], self._psi0[j]
        sigma = clamped - start
        heading = psi0 + k0 * sigma + 0.5 * dk * sigma * sigma
        if dk == 0.0:
            delta = clamped - a
            half_turn = 0.5 * k0 * delta
            chord = delta if half_turn == 0.0 else delta * sin(half_turn) / half_turn
            mid_heading = heading - half_turn
            x = x + chord * cos(mid_heading)
            y = y + chord * sin(mid_heading)
        else:
            half = 0.5 * (clamped - a)
            mid = 0.5 * (clamped + a)
            for i in range(self._n_gauss):
                sigma_node = mid + half * self._nodes[i] - start
                psi = psi0 + k0 * sigma_node + 0.5 * dk * sigma_node * sigma_node
                x = x + half * self._weights[i] * cos(psi)
                y = y + half * self._weights[i] * sin(psi)
        out[2] = heading
        if s == clamped:
            out[0], out[1], out[3] = x, y, k0 + dk * sigma
            return
        beyond = s - clamped
        out[0], out[1], out[3] = x + beyond * cos(heading), y + beyond * sin(heading), 0.0

    def frame(self, double s):
        """``(x, y, heading, κ)`` at progress ``s`` (see ``ReferencePath._frame_python``)."""
        cdef double out[4]
        self._frame(s, out)
        return out[0], out[1], out[2], out[3]

    def newton(self, double px, double py, double s, int max_iterations):
        """Foot point of ``(px, py)`` by Newton from ``s``: ``(s, d, heading, converged)``
        (see ``ReferencePath._newton_python``)."""
        cdef double f[4]
        cdef double tx, ty, ex, ey, d, slope, step
        cdef int it
        for it in range(max_iterations):
            self._frame(s, f)
            tx, ty = cos(f[2]), sin(f[2])
            ex, ey = px - f[0], py - f[1]
            d = -ex * ty + ey * tx
            slope = 1.0 - f[3] * d
            step = (ex * tx + ey * ty) / (0.1 if 0.1 > slope else slope)
            s = s + step
            if fabs(step) < 1e-9:
                return s, d, f[2] + f[3] * step, True
        self._frame(s, f)
        return s, -(px - f[0]) * sin(f[2]) + (py - f[1]) * cos(f[2]), f[2], False
