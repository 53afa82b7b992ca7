"""The planner's model: a dynamic bicycle with tire-force inputs in the road-aligned (Frenet) frame.

One function, usable with numpy arrays (vectorised over trailing axes) and with CasADi symbols, so
the OCP, the sampling roll-outs and the tests all evaluate the very same equations
(Svensson & Törngren, Sec. II; TAMP paper, App. B).

State ``x`` (indexed by :class:`State`): progress ``s`` [m], lateral offset ``d`` [m, left +],
heading error ``dpsi`` [rad], yaw rate ``psidot`` [rad/s], body velocities ``vx``, ``vy`` [m/s].

Input ``u`` (indexed by :class:`Input`): front lateral force ``fyf``, front and rear longitudinal
forces ``fxf``, ``fxr`` [N], all in the vehicle body frame. The rear lateral force is not free: it
follows the rear slip angle through a linear rear tire,
``F_yr = C_r (l_r ψ̇ − v_y) / v_x``, as in the authors' planner; the friction
polygons then bound the whole rear force pair ``(F_xr, F_yr)``.
"""

from __future__ import annotations

import functools
import math
from enum import IntEnum
from typing import Any

import numpy as np

from mufusion.vehicle.params import GRAVITY_MPS2, TireParams, VehicleParams
from mufusion.vehicle.rear_saturation import rear_row_force_n, saturated_rear_force_n
from mufusion.vehicle.surface_tires import SurfaceTireTable, tire_for_surface

# Below this speed the slip-angle expression degenerates; the planner never plans slower than a
# crawl in practice and the bound keeps the model finite at standstill.
MIN_SPEED_FOR_SLIP_MPS = 1.0


class State(IntEnum):
    """Indices of the planner state vector."""

    s = 0
    d = 1
    dpsi = 2
    psidot = 3
    vx = 4
    vy = 5


class Input(IntEnum):
    """Indices of the planner input vector (tire forces in the body frame, N)."""

    fyf = 0
    fxf = 1
    fxr = 2


N_STATES = len(State)
N_INPUTS = len(Input)

# The rows as plain ints for the model's own indexing: on Python 3.11 looking up an IntEnum member
# costs as much as the numpy indexing itself, and the sampling roll-outs evaluate the model some
# two hundred times per planning step.
_D, _DPSI, _PSIDOT = int(State.d), int(State.dpsi), int(State.psidot)
_VX, _VY = int(State.vx), int(State.vy)
_FYF, _FXF, _FXR = int(Input.fyf), int(Input.fxf), int(Input.fxr)


# Argument types that are never CasADi symbols (checked first: the roll-outs call often).
_NUMERIC_TYPES = frozenset({np.ndarray, float, int, np.float64})


def _is_symbolic(*values: Any) -> bool:
    for value in values:
        kind = type(value)
        if kind not in _NUMERIC_TYPES and kind.__module__.startswith("casadi"):
            return True
    return False


def _ops(*values: Any):
    """Math namespace for the arguments: CasADi if any is symbolic, else numpy."""
    if _is_symbolic(*values):
        import casadi as ca

        return ca.sin, ca.cos, ca.fmax, _stack_casadi
    return np.sin, np.cos, np.maximum, _stack_numpy


def _stack_casadi(parts: list[Any], out: None = None) -> Any:
    if out is not None:
        raise ValueError("out must be None for CasADi arguments (symbols cannot be buffered)")
    import casadi as ca

    return ca.vertcat(*parts)


def _stack_numpy(parts: list[Any], out: np.ndarray | None = None) -> np.ndarray:
    """``np.stack(np.broadcast_arrays(*parts))``, without the intermediate views, into ``out``
    when given (the sampling roll-outs call the dynamics a few hundred times per planning step).
    """
    if out is None:
        out = np.empty((len(parts), *np.broadcast(*parts).shape), dtype=np.result_type(*parts))
    for i, part in enumerate(parts):
        out[i] = part
    return out


def rear_cornering_stiffness_n_per_rad(
    params: VehicleParams,
    rear_load_n: Any,
    utilization: float | None = None,
    *,
    mu_hat: Any = None,
    table: SurfaceTireTable | None = None,
) -> Any:
    """Rear-axle cornering stiffness [N/rad] of the planner's linear rear tire.

    Parameters
    ----------
    params
        Vehicle parameters (their :class:`TireParams` give the Magic Formula).
    rear_load_n
        Rear normal load [N] (array or CasADi symbol).
    utilization
        ``None``: the tangent stiffness at zero slip. A value λ in (0, 1]: the *secant* stiffness
        with which the linear tire reaches ``λ μ F_z`` at the same slip angle as the Magic
        Formula does. Below that slip the real tire gives at least the linear force, so a plan
        whose rear force stays inside the λ-sized limit never counts on rear grip the tire cannot
        give; with the tangent stiffness the plan over-estimates rear force near the limit (the
        real tire's curve bends away) and an evasive manoeuvre spins the vehicle.
    mu_hat, table
        ``table=None`` (default): the vehicle's tire, whose stiffness does not depend on μ.
        A :class:`~mufusion.vehicle.surface_tires.SurfaceTireTable`: the stiffness follows the
        estimate ``mu_hat`` (numpy, broadcast with ``rear_load_n``) through the table, as the
        authors' planner computed it (:func:`surface_stiffness_per_load`).

    Raises
    ------
    ValueError
        If ``utilization`` is not in (0, 1], or a table is given without ``mu_hat``.
    """
    if table is not None:
        if mu_hat is None:
            raise ValueError("mu_hat is required when a stiffness table is given")
        return surface_stiffness_per_load(mu_hat, params.tire, table, utilization) * rear_load_n
    stiffness = params.tire.cornering_stiffness_per_load_1_per_rad
    if utilization is not None:
        stiffness = stiffness * secant_stiffness_factor(params.tire, utilization)
    return stiffness * rear_load_n


# Normalised slip B α beyond which a tire curve is searched no further (1000 × its stiffness).
_FAR_SLIP = 1e3


@functools.lru_cache(maxsize=32)
def front_force_rate_limit_n_per_s(params: VehicleParams, utilization: float) -> float:
    """Fastest change of the front lateral force the steering can make [N/s].

    ``K_α · s(λ) · F_z,f · δ̇_max``: the front tire's cornering stiffness per load ``K_α`` at the
    static front load, reduced by the secant factor ``s(λ)`` at the planner's utilisation λ (as
    the rear tire's stiffness is, :func:`rear_cornering_stiffness_n_per_rad`: near the friction
    limit the force follows the slip angle more slowly than at zero slip), times the steering's
    rate limit.

    Examples
    --------
    >>> from mufusion.vehicle.params import TRUCK
    >>> tangent = (TRUCK.tire.cornering_stiffness_per_load_1_per_rad * TRUCK.static_front_load_n
    ...            * TRUCK.max_steer_rate_radps)  # 7/rad · 52.8 kN · 0.9 rad/s
    >>> round(tangent / 1e3), round(front_force_rate_limit_n_per_s(TRUCK, 0.9) / tangent, 3)
    (333, 0.604)
    """
    return (params.tire.cornering_stiffness_per_load_1_per_rad
            * secant_stiffness_factor(params.tire, utilization)
            * params.static_front_load_n * params.max_steer_rate_radps)


@functools.lru_cache(maxsize=32)
def secant_stiffness_factor(tire: TireParams, utilization: float) -> float:
    """Secant / tangent stiffness of the lateral Magic Formula at ``utilization`` of its peak.

    The normalised curve ``F_y / (μ F_z) = sin(C atan(y − E (y − atan y)))`` with
    ``y = B α = K α / (C μ)`` does not depend on μ, so neither does the factor. Raises
    ValueError if ``utilization`` is not in (0, 1].
    """
    if not 0.0 < utilization <= 1.0:
        raise ValueError(f"utilization must be in (0, 1], got {utilization}")
    # SciPy's root finder is imported here, where it is used: importing it with the module took
    # 0.4 s from every command that only reads a scenario (docs/performance.md, "Input errors").
    from scipy.optimize import brentq

    c, e = tire.shape_lateral, tire.curvature_lateral

    def normalised(y: float) -> float:
        return math.sin(c * math.atan(y - e * (y - math.atan(y)))) - utilization

    def past_peak(y: float) -> float:
        return c * math.atan(y - e * (y - math.atan(y))) - math.pi / 2

    # The curve peaks where its inner angle reaches π / (2C); search up to there. A curve whose
    # inner angle never gets there (small C with E = 1, e.g. the authors' racing-tire set) rises
    # monotonically towards its supremum: search far out, where it has all but reached it.
    if past_peak(_FAR_SLIP) >= 0.0:
        peak = brentq(past_peak, 1e-9, _FAR_SLIP)
    elif utilization < 1.0 and normalised(_FAR_SLIP) > 0.0:
        peak = _FAR_SLIP
    else:
        raise ValueError(f"this tire curve never reaches {utilization} of its peak")
    y_star = peak if utilization == 1.0 else brentq(normalised, 1e-12, peak)
    return utilization / (c * y_star)


def surface_stiffness_per_load(
    mu_hat: Any,
    base: TireParams,
    table: SurfaceTireTable,
    utilization: float | None = None,
) -> np.ndarray:
    """Cornering stiffness per unit load [1/rad] a planner assumes for the estimate ``mu_hat``.

    ``B C μ̂`` with the table's coefficients at ``μ̂`` (the authors' ``get_cornering_stiffness``),
    times the secant factor of that set's curve at ``utilization`` (see
    :func:`rear_cornering_stiffness_n_per_rad`). The factor depends on C and E only; it is exact
    at each set (and everywhere in a ``"step"`` table) and interpolated between the sets of a
    ``"linear"`` table like the coefficients themselves: for the authors' interpolated sets that
    is within 0.5 % of the exact factor of the blended curve, and costs no root-finding per
    distinct μ̂ (the sampling roll-outs evaluate thousands per planning step).

    Parameters
    ----------
    mu_hat : array_like
        Friction estimate(s) [-], finite and > 0.
    base : TireParams
        The vehicle's tire (only its longitudinal data are kept by the table's sets).
    table : SurfaceTireTable
    utilization : float, optional
        ``None``: tangent stiffness at zero slip; λ in (0, 1]: the secant stiffness.

    Returns
    -------
    numpy.ndarray
        Shape of ``mu_hat``.

    Raises
    ------
    ValueError
        If a ``mu_hat`` is not finite and > 0, or ``utilization`` is not in (0, 1].

    Examples
    --------
    >>> from mufusion.vehicle.params import TRUCK
    >>> from mufusion.vehicle.surface_tires import AUTHORS_TIRES
    >>> surface_stiffness_per_load([0.4, 0.8], TRUCK.tire, AUTHORS_TIRES).round(2).tolist()
    [4.0, 22.08]
    """
    mu = np.asarray(mu_hat, dtype=float)
    if not np.all(np.isfinite(mu) & (mu > 0.0)):
        raise ValueError("mu_hat must be finite and > 0 everywhere")
    b, c, _ = table.coefficients(mu)
    stiffness = b * c * mu
    if utilization is None:
        return stiffness
    factors = np.array(_anchor_secant_factors(table, base, utilization))
    if table.interpolation == "linear":
        factor = np.interp(mu, np.array(table.mu_points), factors)
    else:
        index = np.clip(np.searchsorted(table.mu_points, mu, side="right") - 1, 0,
                        len(factors) - 1)
        factor = factors[index]
    return stiffness * factor


@functools.lru_cache(maxsize=32)
def _anchor_secant_factors(
    table: SurfaceTireTable, base: TireParams, utilization: float
) -> tuple[float, ...]:
    # The table's first point may be μ = 0 (the authors' ice interval starts there); its set
    # is the same just above.
    return tuple(
        secant_stiffness_factor(tire_for_surface(max(point, 1e-3), base, table), utilization)
        for point in table.mu_points
    )


def rear_lateral_force_n(x: Any, rear_stiffness_n_per_rad: Any, params: VehicleParams,
                         limit_n: Any = None) -> Any:
    """Rear lateral tire force [N] of the planner's linear rear tire.

    ``F_yr = C_r (l_r ψ̇ − v_y) / max(v_x, 1 m/s)``; works on numpy arrays (``x`` of shape
    ``(6, ...)``) and CasADi symbols. ``limit_n`` (> 0, broadcastable; the axle's friction): the
    force the rear polygon prices with the saturated tire (:func:`rear_row_force_n`); ``None``
    keeps it linear.
    """
    fyr = _rear_lateral_force_n(
        x, rear_stiffness_n_per_rad, params, _ops(x, rear_stiffness_n_per_rad)[2]
    )
    return fyr if limit_n is None else rear_row_force_n(fyr, x[_VX], limit_n)


def floored_axle_loads_n(forces: Any, params: VehicleParams, floor_n: float) -> tuple[Any, Any]:
    """Axle loads ``(F_zf, F_zr)`` [N] of the longitudinal forces ``forces[Input.fxf] +
    forces[Input.fxr]`` (pitch load transfer, :func:`normal_loads_n`), each at least
    ``floor_n``; numpy rows or CasADi."""
    total = forces[Input.fxf] + forces[Input.fxr]
    fmax = _ops(total)[2]
    fzf, fzr = normal_loads_n(total / params.mass_kg, params)
    return fmax(fzf, floor_n), fmax(fzr, floor_n)


def _rear_lateral_force_n(x: Any, rear_stiffness_n_per_rad: Any, params: VehicleParams,
                          fmax: Any) -> Any:
    vx = fmax(x[_VX], MIN_SPEED_FOR_SLIP_MPS)
    return rear_stiffness_n_per_rad * (
        params.cog_to_rear_axle_m * x[_PSIDOT] - x[_VY]
    ) / vx


def normal_loads_n(longitudinal_accel_mps2: Any, params: VehicleParams) -> tuple[Any, Any]:
    """Axle normal forces with pitch load transfer [N].

    ``F_zf = m (g l_r − a_x h) / L``, ``F_zr = m (g l_f + a_x h) / L`` (TAMP framework); braking
    (``a_x < 0``) loads the front axle. Works with numpy arrays and CasADi symbols.
    """
    m, h, wheelbase = params.mass_kg, params.cog_height_m, params.wheelbase_m
    fzf = m * (GRAVITY_MPS2 * params.cog_to_rear_axle_m - longitudinal_accel_mps2 * h) / wheelbase
    fzr = m * (GRAVITY_MPS2 * params.cog_to_front_axle_m + longitudinal_accel_mps2 * h) / wheelbase
    return fzf, fzr


def frenet_bicycle_dynamics(
    x: Any,
    u: Any,
    curvature_1pm: Any,
    rear_stiffness_n_per_rad: Any,
    params: VehicleParams,
    out: np.ndarray | None = None,
    rear_force_limit_n: Any = None,
) -> Any:
    """Time derivative of the planner state.

    Parameters
    ----------
    x
        State, shape ``(6, ...)`` (numpy) or a 6-vector CasADi symbol; see :class:`State`.
    u
        Input forces [N], shape ``(3, ...)``; see :class:`Input`.
    curvature_1pm
        Reference-path curvature at the vehicle's progress ``s`` [1/m], left turns positive.
    rear_stiffness_n_per_rad
        Rear axle cornering stiffness [N/rad] (see :func:`rear_cornering_stiffness_n_per_rad`).
    params
        Vehicle parameters.
    out
        Numpy only: array of the result's shape to write ``x_dot`` into (no allocation; the
        values are those of the call without it).
    rear_force_limit_n
        ``None``: the linear rear tire; else the rear lateral force is clipped to ± this
        (:func:`rear_lateral_force_n`), the axle's friction ``μ̂ F_zr`` [N].

    Returns
    -------
    x_dot
        Same shape as ``x`` (``out`` when given): ``ṡ = (v_x cosΔψ − v_y sinΔψ)/(1 − dκ)``,
        ``ḋ = v_x sinΔψ + v_y cosΔψ``,
        ``Δψ̇ = ψ̇ − κṡ``, ``ψ̈ = (l_f F_yf − l_r F_yr)/I_z``, ``v̇_x = (F_xf + F_xr)/m + v_y ψ̇``,
        ``v̇_y = (F_yf + F_yr)/m − v_x ψ̇``.

    Raises
    ------
    ValueError
        If ``out`` is given with CasADi arguments.

    Examples
    --------
    >>> from mufusion.vehicle.params import TRUCK
    >>> x = np.array([0.0, 0.0, 0.0, 0.0, 10.0, 0.0])
    >>> xd = frenet_bicycle_dynamics(x, np.zeros(3), 0.0, 1e5, TRUCK)
    >>> float(xd[State.s])
    10.0
    """
    sin, cos, fmax, stack = _ops(x, u, curvature_1pm, rear_stiffness_n_per_rad)
    d, dpsi, psidot = x[_D], x[_DPSI], x[_PSIDOT]
    vx, vy = x[_VX], x[_VY]
    fyf, fxf, fxr = u[_FYF], u[_FXF], u[_FXR]
    fyr = _rear_lateral_force_n(x, rear_stiffness_n_per_rad, params, fmax)
    if rear_force_limit_n is not None:
        fyr = saturated_rear_force_n(fyr, vx, rear_force_limit_n)
    m = params.mass_kg

    sin_dpsi, cos_dpsi = sin(dpsi), cos(dpsi)
    s_dot = (vx * cos_dpsi - vy * sin_dpsi) / (1.0 - d * curvature_1pm)
    d_dot = vx * sin_dpsi + vy * cos_dpsi
    dpsi_dot = psidot - curvature_1pm * s_dot
    psi_ddot = (
        params.cog_to_front_axle_m * fyf - params.cog_to_rear_axle_m * fyr
    ) / params.yaw_inertia_kgm2
    vx_dot = (fxf + fxr) / m + vy * psidot
    vy_dot = (fyf + fyr) / m - vx * psidot
    return stack([s_dot, d_dot, dpsi_dot, psi_ddot, vx_dot, vy_dot], out)
