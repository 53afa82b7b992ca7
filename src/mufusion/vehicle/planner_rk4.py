"""Batched RK4 steps of the planner's model in numpy, for the sampling roll-outs.

:func:`~mufusion.vehicle.planner_model.frenet_bicycle_dynamics` is the one statement of the model
(numpy and CasADi). Evaluated on a batch of a few dozen states, almost all of its time is numpy's
per-call overhead: about 45 array operations and a stack per evaluation, four evaluations per RK4
step, forty steps per roll-out batch. :class:`BatchRK4` evaluates the same expressions, operand by
operand, into preallocated buffers (sine and cosine once per evaluation, the products with
``v_x`` and ``v_y`` as one operation on both rows, the input terms once per step), so its
results are the reference's bit for bit (``tests/vehicle/test_planner_rk4.py`` checks it).
"""

from __future__ import annotations

import numpy as np

from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import (
    MIN_SPEED_FOR_SLIP_MPS,
    N_STATES,
    Input,
    State,
)

# Positional ``out`` arguments (numpy's keyword handling costs more than the arithmetic here),
# except for np.maximum, whose positional form is deprecated.
_add, _sub, _mul, _div = np.add, np.subtract, np.multiply, np.divide
_sin, _cos, _max = np.sin, np.cos, np.maximum
# Plain ints: indexing with an IntEnum member costs three times as much.
_S, _D, _DPSI, _PSIDOT, _VX, _VY = (int(i) for i in State)
_FYF, _FXF, _FXR = (int(i) for i in Input)


class BatchRK4:
    """Classical RK4 steps (as :func:`~mufusion.planner.sampling.rk4_step`) for M states at once.

    Parameters
    ----------
    params
        Vehicle parameters.
    n_batch
        Number of states M stepped together (≥ 1).

    Raises
    ------
    ValueError
        If ``n_batch`` < 1.

    Examples
    --------
    >>> from mufusion.vehicle.params import TRUCK
    >>> rk4 = BatchRK4(TRUCK, 2)
    >>> x = np.array([[0.0, 0.0], [0.0, 1.0], [0.0, 0.0], [0.0, 0.0], [10.0, 5.0], [0.0, 0.0]])
    >>> out = np.empty_like(x)
    >>> rk4.step(x, np.zeros((3, 2)), np.zeros(2), np.full(2, 1e5), 0.1, out)[State.s].tolist()
    [1.0, 0.5]
    """

    def __init__(self, params: VehicleParams, n_batch: int) -> None:
        if n_batch < 1:
            raise ValueError(f"n_batch must be >= 1, got {n_batch}")
        shape = (N_STATES, n_batch)
        # Constants as 0-d arrays: numpy converts a Python float operand on every call, which
        # costs as much as the operation itself here; the 0-d array holds the same double.
        self._lf, self._lr, self._iz, self._mass, self._one, self._floor, self._two = (
            np.array(float(value))
            for value in (params.cog_to_front_axle_m, params.cog_to_rear_axle_m,
                          params.yaw_inertia_kgm2, params.mass_kg, 1.0, MIN_SPEED_FOR_SLIP_MPS,
                          2.0)
        )
        self._k = [np.empty(shape) for _ in range(4)]
        self._k_rows = [tuple(k) for k in self._k]
        self._stage = np.empty(shape)
        self._stage_rows = self._state_rows(self._stage)
        self._sum = np.empty(shape)
        # (cos Δψ, sin Δψ) and, reversed, (sin Δψ, cos Δψ): multiplied by the rows (v_x, v_y)
        # they give the four products of ṡ and ḋ in two operations.
        self._trig = np.empty((2, n_batch))
        self._trig_rows = tuple(self._trig)
        self._trig_reversed = self._trig[::-1]
        self._with_trig = np.empty((2, n_batch))
        self._with_reversed = np.empty((2, n_batch))
        self._with_trig_rows = tuple(self._with_trig)
        self._with_reversed_rows = tuple(self._with_reversed)
        self._fyr, self._tmp, self._tmp2 = (np.empty(n_batch) for _ in "abc")
        self._lf_fyf = np.empty(n_batch)
        self._fx_over_m = np.empty(n_batch)

    def step(
        self,
        x: np.ndarray,
        u: np.ndarray,
        curvature_1pm: np.ndarray,
        rear_stiffness_n_per_rad: np.ndarray,
        dt_s: float,
        out: np.ndarray,
    ) -> np.ndarray:
        """One RK4 step from ``x (6, M)`` under inputs ``u (3, M)``, written to ``out (6, M)``.

        ``curvature_1pm`` and ``rear_stiffness_n_per_rad``: shape ``(M,)``. Returns ``out``
        (which must not share memory with ``x``); equal bit for bit to ``rk4_step``.
        """
        fyf = u[_FYF]
        # Input terms of ψ̈ and v̇_x: the same in the four evaluations.
        _mul(self._lf, fyf, self._lf_fyf)
        _add(u[_FXF], u[_FXR], self._fx_over_m)
        _div(self._fx_over_m, self._mass, self._fx_over_m)
        k1, k2, k3, k4 = self._k
        r1, r2, r3, r4 = self._k_rows
        stage, stage_rows, total = self._stage, self._stage_rows, self._sum
        half, full = np.array(0.5 * dt_s), np.array(float(dt_s))
        self._derivative(self._state_rows(x), fyf, curvature_1pm, rear_stiffness_n_per_rad, r1)
        _mul(half, k1, stage)
        _add(x, stage, stage)
        self._derivative(stage_rows, fyf, curvature_1pm, rear_stiffness_n_per_rad, r2)
        _mul(half, k2, stage)
        _add(x, stage, stage)
        self._derivative(stage_rows, fyf, curvature_1pm, rear_stiffness_n_per_rad, r3)
        _mul(full, k3, stage)
        _add(x, stage, stage)
        self._derivative(stage_rows, fyf, curvature_1pm, rear_stiffness_n_per_rad, r4)
        # x + dt/6 (k1 + 2 k2 + 2 k3 + k4), summed left to right as the reference does.
        _mul(self._two, k2, total)
        _add(k1, total, total)
        _mul(self._two, k3, stage)
        _add(total, stage, total)
        _add(total, k4, total)
        _mul(np.array(dt_s / 6.0), total, total)
        return _add(x, total, out)

    @staticmethod
    def _state_rows(x: np.ndarray) -> tuple[np.ndarray, ...]:
        """Views of ``x``: d, Δψ, ψ̇, v_x, v_y and the two speed rows together."""
        return x[_D], x[_DPSI], x[_PSIDOT], x[_VX], x[_VY], x[_VX : _VY + 1]

    def _derivative(
        self,
        x_rows: tuple[np.ndarray, ...],
        fyf: np.ndarray,
        kappa: np.ndarray,
        rear_stiffness: np.ndarray,
        rows: tuple[np.ndarray, ...],
    ) -> None:
        """``frenet_bicycle_dynamics(x, u, κ, C_r)`` into ``rows`` (the input terms precomputed)."""
        d, dpsi, psidot, vx, vy, speeds = x_rows
        s_dot, d_dot, dpsi_dot, psi_ddot, vx_dot, vy_dot = rows
        cos, sin = self._trig_rows
        fyr, tmp, tmp2 = self._fyr, self._tmp, self._tmp2
        vx_cos, vy_sin = self._with_trig_rows
        vx_sin, vy_cos = self._with_reversed_rows
        _cos(dpsi, cos)
        _sin(dpsi, sin)
        _mul(speeds, self._trig, self._with_trig)
        _mul(speeds, self._trig_reversed, self._with_reversed)
        # ṡ = (v_x cosΔψ − v_y sinΔψ) / (1 − d κ)
        _sub(vx_cos, vy_sin, tmp2)
        _mul(d, kappa, tmp)
        _sub(self._one, tmp, tmp)
        _div(tmp2, tmp, s_dot)
        # ḋ = v_x sinΔψ + v_y cosΔψ
        _add(vx_sin, vy_cos, d_dot)
        # Δψ̇ = ψ̇ − κ ṡ
        _mul(kappa, s_dot, tmp)
        _sub(psidot, tmp, dpsi_dot)
        # F_yr = C_r (l_r ψ̇ − v_y) / max(v_x, 1 m/s)  (rear_lateral_force_n)
        _max(vx, self._floor, out=tmp)
        _mul(self._lr, psidot, fyr)
        _sub(fyr, vy, fyr)
        _mul(rear_stiffness, fyr, fyr)
        _div(fyr, tmp, fyr)
        # ψ̈ = (l_f F_yf − l_r F_yr) / I_z
        _mul(self._lr, fyr, tmp)
        _sub(self._lf_fyf, tmp, tmp)
        _div(tmp, self._iz, psi_ddot)
        # v̇_x = (F_xf + F_xr)/m + v_y ψ̇
        _mul(vy, psidot, tmp)
        _add(self._fx_over_m, tmp, vx_dot)
        # v̇_y = (F_yf + F_yr)/m − v_x ψ̇
        _add(fyf, fyr, tmp)
        _div(tmp, self._mass, tmp)
        _mul(vx, psidot, tmp2)
        _sub(tmp, tmp2, vy_dot)


__all__ = ["BatchRK4"]
