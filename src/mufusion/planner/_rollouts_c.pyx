# cython: language_level=3, boundscheck=False, wraparound=False, cdivision=True, initializedcheck=False
"""Compiled loop of :func:`mufusion.planner.sampling.candidate_rollouts` (same values, bit for bit).

The numpy roll-out calls some fifty array operations per step on a few dozen candidates, so its
time is the operations' call overhead. Here the elementwise arithmetic runs in C loops, in the
numpy code's operand order; IEEE-754 rounds each operation as numpy's ufuncs do. What numpy
computes with its own machine-dependent routines (``sin``, ``cos``, ``arctan2``) is still
computed by numpy on the whole candidate vector, and the road's curvature, μ̂ and the rear
stiffness come from the same Python callables, so the results equal the numpy roll-out's on
any machine. ``maximum``/``minimum`` follow numpy's scalar rule (NaN propagates; on a tie the
first operand). The build turns off floating-point contraction (no fused multiply-adds).
"""

import numpy as np

from libc.math cimport isnan, sqrt


_MINUS_BRAKE_SHARE = -0.8


cdef inline double nmax(double a, double b) noexcept nogil:
    return a if (a >= b or isnan(a)) else b


cdef inline double nmin(double a, double b) noexcept nogil:
    return a if (a <= b or isnan(a)) else b


cdef void dynamics(
    const double[:, ::1] x, const double[:, ::1] u, const double[::1] kappa,
    const double[::1] c_r, const double[::1] sin_dpsi, const double[::1] cos_dpsi,
    const double* k, double[:, ::1] out, Py_ssize_t n,
) noexcept nogil:
    # frenet_bicycle_dynamics; k = (m, lf, lr, iz, min speed for slip).
    cdef Py_ssize_t j
    cdef double d, psidot, vx, vy, fyf, fxf, fxr, fyr, s_dot
    for j in range(n):
        d, psidot, vx, vy = x[1, j], x[3, j], x[4, j], x[5, j]
        fyf, fxf, fxr = u[0, j], u[1, j], u[2, j]
        fyr = c_r[j] * (k[2] * psidot - vy) / nmax(vx, k[4])
        s_dot = (vx * cos_dpsi[j] - vy * sin_dpsi[j]) / (1.0 - d * kappa[j])
        out[0, j] = s_dot
        out[1, j] = vx * sin_dpsi[j] + vy * cos_dpsi[j]
        out[2, j] = psidot - kappa[j] * s_dot
        out[3, j] = (k[1] * fyf - k[2] * fyr) / k[3]
        out[4, j] = (fxf + fxr) / k[0] + vy * psidot
        out[5, j] = (fyf + fyr) / k[0] - vx * psidot


def rollouts(
    double[:, :, ::1] xs,
    double[:, :, ::1] us,
    const double[::1] d_t,
    const double[::1] v_t,
    curvature_of_s,
    mu_hat_of_s,
    stiffness_of,
    tuple constants,
    double stiffness_per_load=0.0,
):
    """Fill ``xs (N+1, 6, M)`` (``xs[0]`` given) and ``us (N, 3, M)`` as the numpy roll-out does.

    ``curvature_of_s`` and ``mu_hat_of_s`` map the candidates' ``s`` to arrays of shape ``(M,)``;
    ``stiffness_of(rear_load, mu)`` gives the rear cornering stiffness, or, ``None``, it is
    ``stiffness_per_load`` times the rear load (the vehicle's tire: numpy's product of a float and
    an array, the same IEEE multiplication here); ``constants`` are the Python floats the numpy
    code computes with (see ``sampling._rollout_constants``).
    """
    cdef double m, lf, lr, iz, min_slip_speed, g_lr, g_lf, h, wheelbase, share_front
    cdef double share_front_m, yaw_term, speed_force, min_lookahead, lookahead_time
    cdef double heading_gain, lower0, lower1, upper0, upper1, utilization, dt
    (m, lf, lr, iz, min_slip_speed, g_lr, g_lf, h, wheelbase, share_front, share_front_m,
     yaw_term, speed_force, min_lookahead, lookahead_time, heading_gain, lower0, lower1,
     upper0, upper1, utilization, dt) = constants
    # The literal as a value the C compiler cannot see: it may rewrite ``-0.8 * x`` as
    # ``-(0.8 * x)``, the same number except for the sign of a NaN (numpy multiplies).
    cdef double minus_brake_share = _MINUS_BRAKE_SHARE
    cdef double dyn[5]
    dyn[0], dyn[1], dyn[2], dyn[3], dyn[4] = m, lf, lr, iz, min_slip_speed
    cdef Py_ssize_t n_steps = us.shape[0], n = xs.shape[2], step, j, i, stage
    cdef double half = 0.5 * dt, sixth = dt / 6.0, scale
    cdef double[::1] ax = np.zeros(n)
    cdef double[::1] fzr = np.empty(n)
    cdef double[::1] mu_stiffness = np.empty(n)
    cdef double[::1] v = np.empty(n)
    cdef double[::1] kappa, mu, c_r, dpsi_des
    cdef object offset = np.empty(n), lookahead = np.empty(n), dpsi = np.empty(n)
    cdef double[::1] offset_v = offset, lookahead_v = lookahead, dpsi_v = dpsi
    # numpy's sin, cos and arctan2 write into these (the same values as into new arrays).
    cdef object sin_out = np.empty(n), cos_out = np.empty(n), atan_out = np.empty(n)
    cdef double[::1] sin_dpsi = sin_out, cos_dpsi = cos_out
    cdef bint fixed_tire = stiffness_of is None
    cdef double[::1] c_r_fixed = np.empty(n)
    cdef double[:, ::1] x, u, x_next
    cdef double[:, :, ::1] ks = np.empty((4, 6, n))
    cdef double[:, ::1] x_stage = np.empty((6, n))
    cdef double fzf, vx, r_des, fyf, f_long, fxf, fxr, limit_mu, limit_f, limit_r, lat_room
    cdef double total
    for step in range(n_steps):
        x = xs[step]
        u = us[step]
        s = np.asarray(x[0])
        kappa = _per_candidate(curvature_of_s(s), n)
        mu = _per_candidate(mu_hat_of_s(s), n)
        for j in range(n):
            v[j] = nmax(x[4, j], 1.0)
            fzr[j] = m * (g_lf + ax[j] * h) / wheelbase
            # A diverged candidate (discarded by the caller) may sit where μ̂ is not finite.
            mu_stiffness[j] = mu[j] if (mu[j] - mu[j] == 0.0 and mu[j] > 0.0) else 1.0
            lookahead_v[j] = nmax(min_lookahead, lookahead_time * v[j])
            offset_v[j] = d_t[j] - x[1, j]
        if fixed_tire:
            for j in range(n):
                c_r_fixed[j] = stiffness_per_load * fzr[j]
            c_r = c_r_fixed
        else:
            c_r = _per_candidate(stiffness_of(np.asarray(fzr), np.asarray(mu_stiffness)), n)
        dpsi_des = np.arctan2(offset, lookahead, out=atan_out)
        for j in range(n):
            vx = x[4, j]
            fzf = m * (g_lr - ax[j] * h) / wheelbase
            r_des = kappa[j] * v[j] + heading_gain * (dpsi_des[j] - x[2, j])
            fyf = share_front_m * v[j] * r_des + yaw_term * (r_des - x[3, j])
            f_long = speed_force * (v_t[j] - vx)
            if f_long < 0.0:
                fxf = share_front * f_long
                fxr = (1.0 - share_front) * f_long
            else:
                fxf = 0.0
                fxr = f_long
            limit_mu = utilization * mu[j]
            limit_f = limit_mu * fzf
            limit_r = limit_mu * fzr[j]
            fxf = nmin(nmax(fxf, nmax(lower0, minus_brake_share * limit_f)), upper0)
            fxr = nmin(nmax(fxr, nmax(lower1, minus_brake_share * limit_r)), nmin(upper1, 0.8 * limit_r))
            lat_room = sqrt(nmax(limit_f * limit_f - fxf * fxf, 0.0)) * 0.95
            u[0, j] = nmin(nmax(fyf, -lat_room), lat_room)
            u[1, j] = fxf
            u[2, j] = fxr
            ax[j] = (fxf + fxr) / m
        # Classical RK4 (sampling.rk4_step): k1..k4 at x, x + dt/2 k1, x + dt/2 k2, x + dt k3.
        for stage in range(4):
            if stage == 0:
                x_stage[:, :] = x
            else:
                scale = dt if stage == 3 else half
                for i in range(6):
                    for j in range(n):
                        x_stage[i, j] = x[i, j] + scale * ks[stage - 1, i, j]
            dpsi_v[:] = x_stage[2]
            np.sin(dpsi, out=sin_out)
            np.cos(dpsi, out=cos_out)
            dynamics(x_stage, u, kappa, c_r, sin_dpsi, cos_dpsi, dyn, ks[stage], n)
        x_next = xs[step + 1]
        for i in range(6):
            for j in range(n):
                total = ks[0, i, j] + 2.0 * ks[1, i, j]
                total = total + 2.0 * ks[2, i, j]
                total = total + ks[3, i, j]
                x_next[i, j] = x[i, j] + sixth * total
        for j in range(n):
            x_next[4, j] = nmax(x_next[4, j], 0.0)


cdef _per_candidate(value, Py_ssize_t n):
    """``value`` as a contiguous float array of shape ``(n,)`` (sampling._per_candidate)."""
    array = np.asarray(value, dtype=float)
    if array.shape != (n,):
        array = array * np.ones(n)
    return np.ascontiguousarray(array)
