# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled passes of :mod:`mufusion.planner.speed_profile` (same values, bit for bit).

The backward and forward passes over the profile's grid are sequential loops of a few scalar
operations per metre; in Python each costs the interpreter's dispatch. Here they run in C on the
same IEEE operations in the same order (``sqrt`` is correctly rounded in both), with Python's
``min``/``max`` argument rule: ``max(a, b)`` is ``b`` only if ``b > a`` and ``min(a, b)`` is
``b`` only if ``b < a`` (so a NaN in the first argument propagates, as there). The build turns
off floating-point contraction (no fused multiply-adds). The forward pass divides by the
friction: a zero or negative one, on which the Python loop raises, never reaches it (the
caller keeps the Python loop for those).
"""

from libc.math cimport sqrt


cdef inline double pmax(double a, double b) noexcept nogil:
    return b if b > a else a


cdef inline double pmin(double a, double b) noexcept nogil:
    return b if b < a else a


cdef enum:
    BISECTION_STEPS = 32  # mufusion.planner.axle_reach.BISECTION_STEPS


cdef inline double reach_left(double b, double r, double p, double q, double eta) noexcept nogil:
    cdef double front = p + eta * b, rear = q - eta * b
    cdef double rear_sq = rear * rear - (r * q) * (r * q)
    return (sqrt(front * front - (r * p) * (r * p))
            + sqrt(rear_sq if rear_sq > 0.0 else 0.0) - b)


cdef inline double two_axle_braking(double a, double lateral, double p, double hl,
                                   double g) noexcept nogil:
    """``mufusion.planner.axle_reach.two_axle_braking_mps2``, operation for operation."""
    cdef double r, q, eta, hi, lo, mid
    cdef int k
    if a <= 0.0:
        return 0.0
    r = lateral / a
    if r < 0.0:
        r = -r
    if r >= 1.0:
        return 0.0
    if r == 0.0:
        return a
    q = 1.0 - p
    eta = a / g * hl
    hi = sqrt(1.0 - r * r)
    if eta > 0.0 and q * (1.0 - r) / eta < hi:
        hi = q * (1.0 - r) / eta
    if reach_left(hi, r, p, q, eta) >= 0.0:
        return a * hi
    lo = 0.0
    for k in range(BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        if reach_left(mid, r, p, q, eta) >= 0.0:
            lo = mid
        else:
            hi = mid
    return a * lo


def backward_pass(double[::1] u, const double[::1] kappa, const double[::1] accel,
                  const double[::1] s, double two_b, double p=0.0, double hl=-1.0,
                  double g=0.0):
    """In place on ``u`` (squared speeds, already capped by the curvature and the end speed):
    each point lowered to what braking with ``two_b / 2`` of the friction left after the
    larger curvature's lateral demand reaches from the next point (``hl >= 0``: the two axles'
    reach with front share ``p``, height per wheelbase ``hl`` and gravity ``g``; else the point
    mass's)."""
    cdef Py_ssize_t n = u.shape[0], i
    cdef double u_next, k_next, s_next, k_i, s_i, a, lateral, braking, reachable
    if n == 0:
        return
    u_next, k_next, s_next = u[n - 1], kappa[n - 1], s[n - 1]
    with nogil:
        for i in range(n - 2, -1, -1):
            k_i, s_i, a = kappa[i], s[i], accel[i]
            lateral = u_next * (k_next if k_next > k_i else k_i)
            if hl >= 0.0:
                braking = two_axle_braking(a, lateral, p, hl, g)
            else:
                braking = sqrt(pmax(a * a - lateral * lateral, 0.0))
            reachable = u_next + two_b * braking * (s_next - s_i)
            u_next = reachable if reachable < u[i] else u[i]
            u[i] = u_next
            k_next, s_next = k_i, s_i


def forward_pass(double[::1] out, const double[::1] cap, const double[::1] kappa,
                 const double[::1] accel, const double[::1] s, double w, Py_ssize_t bottom,
                 double max_accel):
    """Writes the regained squared speeds into ``out`` (``out[0] = w``): held below ``cap``
    up to ``bottom``, then rising with the drive's cap on the g-g ellipse."""
    cdef Py_ssize_t n = cap.shape[0], i
    cdef double lateral, ratio
    out[0] = w
    with nogil:
        for i in range(n - 1):
            if i < bottom:
                w = pmin(cap[i + 1], w)
            else:
                lateral = w * pmax(kappa[i], kappa[i + 1])
                ratio = pmin(lateral / accel[i], 1.0)
                w = pmin(cap[i + 1], w + 2.0 * max_accel * sqrt(1.0 - ratio * ratio)
                         * (s[i + 1] - s[i]))
            out[i + 1] = w


def descent_pass(double[::1] out, const double[::1] floor, const double[::1] kappa,
                 const double[::1] accel, const double[::1] s, double w, double fraction,
                 double p=0.0, double hl=-1.0, double g=0.0):
    """Writes into ``out`` the squared speeds of braking from ``w`` with what the cornering
    leaves of ``fraction`` of the friction, never below ``floor`` (``out[0] = max(w,
    floor[0])``; ``p``, ``hl``, ``g`` as for :func:`backward_pass`)."""
    cdef Py_ssize_t n = floor.shape[0], i
    cdef double lateral, braking, share
    if n == 0:
        return
    w = pmax(w, floor[0])
    out[0] = w
    with nogil:
        for i in range(n - 1):
            lateral = w * pmax(kappa[i], kappa[i + 1])
            share = fraction * accel[i]
            if hl >= 0.0:
                braking = two_axle_braking(share, lateral, p, hl, g)
            else:
                braking = sqrt(pmax(share * share - lateral * lateral, 0.0))
            w = pmax(w - 2.0 * braking * (s[i + 1] - s[i]), floor[i + 1])
            out[i + 1] = w
