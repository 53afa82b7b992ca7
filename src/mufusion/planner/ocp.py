"""Backend-independent description of the traction-adaptive OCP (Svensson & Törngren, Sec. II).

Small factories assemble the pieces: per-stage parameters (curvature, rear stiffness, polygon
radii), friction polygons and their constraint expressions, actuator bounds on the longitudinal
forces, the lateral corridor from lanes and obstacles, the tracking reference and weights, and
the slack penalties. Both backends (acados RTI, CasADi + IPOPT reference) build their problem
from these pieces only, and implement :class:`~mufusion.planner.backend.PlannerBackend`. What
configures the problem is apart, in :mod:`mufusion.planner.config`.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from enum import IntEnum
from typing import Any

import numpy as np

# Importers of this module keep the configuration's names.
from mufusion.planner.config import CostWeights as CostWeights
from mufusion.planner.config import PlannerConfig as PlannerConfig
from mufusion.planner.config import PlannerMode as PlannerMode
from mufusion.planner.config import PlannerObstacle as PlannerObstacle
from mufusion.planner.config import PlausibilityLimits as PlausibilityLimits
from mufusion.planner.corridor import MAX_SWING_HEADING_RAD as MAX_SWING_HEADING_RAD
from mufusion.planner.corridor import heading_rows as heading_rows
from mufusion.planner.corridor import lateral_corridor as lateral_corridor
from mufusion.planner.penalties import SlackPenalties as SlackPenalties
from mufusion.planner.penalties import slack_penalties as slack_penalties
from mufusion.planner.plan import StageParameters
from mufusion.planner.under_axles import lowest_ahead
from mufusion.vehicle.params import GRAVITY_MPS2, VehicleParams
from mufusion.vehicle.planner_model import (
    N_INPUTS,
    N_STATES,
    Input,
    State,
    floored_axle_loads_n,
    normal_loads_n,
    rear_cornering_stiffness_n_per_rad,
    rear_lateral_force_n,
)
from mufusion.vehicle.surface_tires import SurfaceTireTable

# Upper bound on v_x at stages 1..N [m/s]: inactive in practice, it keeps the box finite.
MAX_SPEED_MPS = 100.0
# Lower bound of a one-sided (normalised) friction-polygon row: inactive, acados needs a finite
# one (this build does not mask infinite bounds: at -1e10 a solve took 5.3 instead of 1.85 ms).
POLYGON_ROW_LOWER_BOUND = -1e3


class Param(IntEnum):
    """Per-stage parameter vector ``p``."""

    curvature = 0
    rear_stiffness = 1
    radius_front = 2
    radius_rear = 3
    # λ μ̂: with ``PlannerConfig.load_transfer`` the polygons' radii are this times the axle
    # loads of the plan's own longitudinal forces; the radii above (at the guess's loads) then
    # only scale the rows.
    utilized_friction = 4
    # The reference point's lane bounds at the stage [m]: the heading rows keep the body's ends
    # within them (corridor.heading_rows); ±HEADING_ROWS_OFF_M leaves the rows slack.
    lane_lo = 5
    lane_hi = 6
    # λ μ̂ of the front polygon: the lower of the CoG's μ̂ and the front axle's, where the front
    # tires are (docs/decisions/0112); the rear polygon keeps ``utilized_friction``.
    utilized_friction_front = 7


N_PARAMS = len(Param)
HEADING_ROWS = 4
"""Rows per stage that keep the body's front and rear ends in the lane (soft, one-sided, in m)."""
HEADING_ROWS_OFF_M = 100.0
"""Lane bounds this far out leave the heading rows slack (stage 0, evasion)."""

# Range of μ̂ the planner accepts per stage; finite values outside are clipped to it (see
# :mod:`mufusion.planner.safeguards` for non-finite ones).
MU_MIN = 0.05
MU_MAX = 2.0

MIN_LOAD_SHARE = 0.05
"""Floor of an axle's normal load in the polygons, as a share of the weight."""


def axle_loads_n(inputs: np.ndarray, params: VehicleParams) -> tuple[np.ndarray, np.ndarray]:
    """Axle loads ``(F_zf, F_zr)`` [N] per stage of ``inputs (N, 3)``: pitch load transfer of
    ``a_x = (F_xf + F_xr) / m``, floored at :data:`MIN_LOAD_SHARE` of the weight (polygons')."""
    return floored_axle_loads_n(np.asarray(inputs, dtype=float).T, params,
                                MIN_LOAD_SHARE * params.mass_kg * GRAVITY_MPS2)


def longitudinal_force_bounds_n(params: VehicleParams) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on ``(F_xf, F_xr)`` [N] from the actuators: the front axle only brakes (the
    :class:`~mufusion.vehicle.actuators.ActuatorCommand` clips front drive torque), the rear
    drives and brakes. Inputs, so they are hard."""
    r = params.wheel_radius_m
    lower = np.array([-params.max_brake_torque_front_nm / r, -params.max_brake_torque_rear_nm / r])
    upper = np.array([0.0, params.max_drive_torque_nm / r])
    return lower, upper


@functools.lru_cache(maxsize=8)
def polygon_directions(n_sides: int) -> tuple[np.ndarray, float]:
    """Outward normals ``(n, 2)`` over ``(F_x, F_y)`` and the inscribed-radius ratio ``cos(π/n)``.

    A regular n-gon inscribed in the circle of radius R is ``{f : n_j · f ≤ R cos(π/n)}``.
    Cached (every solution check uses them); the normals are read-only.
    """
    theta = 2.0 * np.pi * np.arange(n_sides) / n_sides
    normals = np.stack([np.cos(theta), np.sin(theta)], axis=1)
    normals.flags.writeable = False
    return normals, float(np.cos(np.pi / n_sides))


def stage_parameters(
    guess_states: np.ndarray,
    guess_inputs: np.ndarray,
    curvature_of_s,
    mu_hat_of_s,
    params: VehicleParams,
    utilization_factor: float,
    stiffness_table: SurfaceTireTable | None = None,
    axle_lag_s: float | None = None,
    polygon_sides: int = 12,
    front_axle: bool = False,
) -> StageParameters:
    """Per-stage parameters from the initial guess (predicted ``s_k`` and ``a_x,k``).

    ``stiffness_table``: ``None`` keeps the rear stiffness of the vehicle's tire; a table makes
    it follow each stage's μ̂ (``PlannerConfig.stiffness = "from_mu_hat"``).
    Both polygons take μ̂ at the centre of gravity's ``s_k``; with ``front_axle`` the front
    polygon takes the lower of that and the front axle's (``mu_hat_front``).
    ``axle_lag_s``: ``None`` bounds the front braking by the polygon only; a torque lag [s]
    also bounds it where the front axle meets a lower μ̂ than the front polygon's between the
    stage's start and where a brake torque commanded then lands (``v_k`` times the lag further,
    :func:`~mufusion.planner.under_axles.lowest_ahead`): at the polygon's braking face at that
    μ̂ (:func:`front_brake_limit_n`; ``inf`` elsewhere).

    Returns a :class:`StageParameters`: arrays of length N and the stacked ``p``.
    """
    s_k = guess_states[:-1, State.s]
    fzf, fzr = axle_loads_n(guess_inputs, params)
    axle = None
    if axle_lag_s is not None:
        reach = np.maximum(guess_states[:-1, State.vx], 0.0) * axle_lag_s
        axle = _clipped_mu(lowest_ahead(mu_hat_of_s, s_k + params.cog_to_front_axle_m, reach))
    # The front tires meet a drop l_f before the CoG: the front polygon takes the lower of the
    # two μ̂ (docs/decisions/0112); the rear keeps the CoG's (the road behind it is a record
    # that a safe-mode estimate leaves stale, 0099). The stages' own query last: a sanitising
    # μ̂ (planner/safeguards.py) counts the values it replaced in its latest query, and the
    # plan reports that count for its stages.
    front = _clipped_mu(mu_hat_of_s(s_k + params.cog_to_front_axle_m)) if front_axle else np.inf
    mu = _clipped_mu(mu_hat_of_s(s_k))
    mu_front = mu_brake = np.minimum(front, mu)
    if axle is not None:
        mu_brake = np.minimum(mu_front, axle)
    kappa = np.asarray(curvature_of_s(s_k), dtype=float) * np.ones_like(s_k)
    c_r = rear_cornering_stiffness_n_per_rad(
        params, fzr, utilization_factor, mu_hat=mu, table=stiffness_table
    )
    radius_front = utilization_factor * mu_front * fzf
    radius_rear = utilization_factor * mu * fzr
    p = np.zeros((s_k.size, N_PARAMS))
    p[:, Param.curvature] = kappa
    p[:, Param.rear_stiffness] = c_r
    p[:, Param.radius_front] = radius_front
    p[:, Param.radius_rear] = radius_rear
    utilized = utilization_factor * mu
    p[:, Param.utilized_friction] = utilized
    p[:, Param.utilized_friction_front] = utilization_factor * mu_front
    p[:, Param.lane_lo], p[:, Param.lane_hi] = -HEADING_ROWS_OFF_M, HEADING_ROWS_OFF_M
    brake = np.full(s_k.shape, np.inf)
    lower = mu_brake < mu_front
    if np.any(lower):
        brake[lower] = front_brake_limit_n(
            polygon_directions(polygon_sides)[1] * utilization_factor * mu_brake[lower],
            np.asarray(guess_inputs, dtype=float)[lower, Input.fxr], params)
    return StageParameters(mu, fzf, fzr, radius_front, radius_rear, utilized, c_r, kappa, p,
                           mu_brake, brake, mu_front)


def front_brake_limit_n(
    face_friction: np.ndarray, fxr_n: np.ndarray, params: VehicleParams
) -> np.ndarray:
    """The front braking [N] at a polygon's braking face ``k F_zf`` (``face_friction`` k:
    ``cos(π/n) λ μ̂``) at the load that braking itself puts on the front axle, with the rear
    force ``fxr_n``: ``F_b = k (F_zf,static − F_xr h / L) / (1 − k h / L)``."""
    k = np.asarray(face_friction, dtype=float)
    slope = params.cog_height_m / params.wheelbase_m
    static = normal_loads_n(0.0, params)[0]
    return k * (static - np.asarray(fxr_n, dtype=float) * slope) / (1.0 - k * slope)


def _clipped_mu(mu: Any) -> np.ndarray:
    """μ̂ clipped to [:data:`MU_MIN`, :data:`MU_MAX`]."""
    # np.minimum(np.maximum(...)): np.clip's values (non-zero bounds) at less overhead.
    return np.minimum(np.maximum(np.asarray(mu, dtype=float), MU_MIN), MU_MAX)


def plan_rear_stiffness(c_r: Any, guess_rear_load_n: Any, forces: Any, params: VehicleParams,
                        load_transfer: bool) -> Any:
    """The linear rear tire's stiffness [N/rad] at the plan's own rear load: with
    ``load_transfer`` the stage's ``c_r`` (at the guess's load ``guess_rear_load_n``) times the
    ratio of the loads, as the polygons take them (a tire's stiffness is proportional to its
    load; docs/decisions/0066); without, ``c_r``. numpy (``forces (3, N)``) or CasADi."""
    if not load_transfer:
        return c_r
    floor = MIN_LOAD_SHARE * params.mass_kg * GRAVITY_MPS2
    return c_r * floored_axle_loads_n(forces, params, floor)[1] / guess_rear_load_n


def ocp_rear_stiffness(p: Any, forces: Any, params: VehicleParams, load_transfer: bool) -> Any:
    """:func:`plan_rear_stiffness` of a stage's parameter vector ``p`` (CasADi)."""
    guess_load = p[Param.radius_rear] / p[Param.utilized_friction]
    return plan_rear_stiffness(p[Param.rear_stiffness], guess_load, forces, params, load_transfer)


def plan_polygon_radii_n(
    inputs: np.ndarray, stage: StageParameters, params: VehicleParams, load_transfer: bool
) -> tuple[np.ndarray, np.ndarray]:
    """The friction polygons' radii ``(front, rear)`` [N] a plan ``inputs (N, 3)`` was solved with.

    Without ``load_transfer`` these are the stage parameters (the guess's axle loads); with it,
    ``λ μ̂`` times the loads of the plan's own longitudinal forces (:func:`constraint_expressions`).
    """
    if not load_transfer:
        return stage.radius_front_n, stage.radius_rear_n
    fzf, fzr = axle_loads_n(inputs, params)
    return stage.p[:, Param.utilized_friction_front] * fzf, stage.utilized_friction * fzr


@dataclass(frozen=True)
class PolygonRows:
    """How the friction polygons enter the OCP: ``lower ≤ h ≤ upper`` row by row.

    ``per_axle`` rows for the front axle (hard), then as many for the rear (soft). Where the
    radii are parameters (no load transfer) an even polygon's opposite faces are parallel
    (``n_{j+n/2} = -n_j``), so ``n_j · f ≤ R cos(π/n)`` for all ``j`` is ``|n_j · f| ≤ R cos(π/n)``
    for ``j < n/2``: half the rows, each two-sided, with the same feasible set and no artificial
    bound (``two_sided``). With load transfer the radius depends on the stage's own forces, so a
    face and its opposite bind at different affine bounds and each face is its own one-sided row
    (``n·f − R(f) ≤ 0``, lower bound :data:`POLYGON_ROW_LOWER_BOUND`).
    """

    per_axle: int
    lower: float
    upper: float
    two_sided: bool

    @property
    def count(self) -> int:
        """Rows of both axles."""
        return 2 * self.per_axle


def polygon_rows(n_sides: int, *, load_transfer: bool) -> PolygonRows:
    """The row layout of :func:`constraint_expressions` (the one place both backends read it).

    Examples
    --------
    >>> polygon_rows(12, load_transfer=False)
    PolygonRows(per_axle=6, lower=-0.9659258262890683, upper=0.9659258262890683, two_sided=True)
    >>> polygon_rows(12, load_transfer=True).count
    24
    """
    if n_sides % 2:
        raise ValueError(f"polygon_sides must be even, got {n_sides}")
    ratio = polygon_directions(n_sides)[1]
    if load_transfer:
        return PolygonRows(n_sides, POLYGON_ROW_LOWER_BOUND, 0.0, two_sided=False)
    return PolygonRows(n_sides // 2, -ratio, ratio, two_sided=True)


def constraint_expressions(
    x: Any, u: Any, p: Any, params: VehicleParams, n_sides: int, *, load_transfer: bool,
    heading: bool = False, rear_force_limit_n: Any = None,
) -> Any:
    """Friction polygons normalised by their radii, as CasADi rows (bounds: :func:`polygon_rows`),
    then, with ``heading``, the :data:`HEADING_ROWS` of :func:`~.corridor.heading_rows` (soft,
    ``≤ 0`` in metres, lower bound :data:`POLYGON_ROW_LOWER_BOUND`; ``PlannerConfig.heading_rows``).

    Rows: the front polygon over ``(F_xf, F_yf)`` (hard), then the rear polygon over
    ``(F_xr, F_yr(x))`` (soft; see :func:`slack_penalties`). Without ``load_transfer`` the radii
    are the parameters (at the guess's axle loads) and the rows are the slabs
    ``n_j · f / R`` (``j < n/2``) within ``±cos(π/n)``; with it, each radius is ``λ μ̂ F_z`` at the
    loads of the stage's own ``F_xf + F_xr`` (linear in the forces, floored at 5 % of the weight
    as in :func:`stage_parameters`) and the ``n`` rows are ``(n_j · f − R(f)) / R ≤ 0``, divided
    by the parameter radii. ``rear_force_limit_n`` (``PlannerConfig.rear_saturation``): ``F_yr``
    of the saturated rear tire at that friction (:func:`~mufusion.vehicle.rear_saturation.
    rear_row_force_n`); ``None``: the linear tire's.
    """
    import casadi as ca

    normals, ratio = polygon_directions(n_sides)
    fyr = rear_lateral_force_n(x, ocp_rear_stiffness(p, u, params, load_transfer), params,
                               rear_force_limit_n)
    if not load_transfer:
        half = normals[: polygon_rows(n_sides, load_transfer=False).per_axle]
        front = [(nx * u[Input.fxf] + ny * u[Input.fyf]) / p[Param.radius_front]
                 for nx, ny in half]
        rear = [(nx * u[Input.fxr] + ny * fyr) / p[Param.radius_rear] for nx, ny in half]
        return ca.vertcat(*front, *rear, *(_heading_rows(x, p, params) if heading else ()))
    fzf, fzr = floored_axle_loads_n(u, params, MIN_LOAD_SHARE * params.mass_kg * GRAVITY_MPS2)
    limit_front = ratio * p[Param.utilized_friction_front] * fzf
    limit_rear = ratio * p[Param.utilized_friction] * fzr
    front = [(nx * u[Input.fxf] + ny * u[Input.fyf] - limit_front) / p[Param.radius_front]
             for nx, ny in normals]
    rear = [(nx * u[Input.fxr] + ny * fyr - limit_rear) / p[Param.radius_rear]
            for nx, ny in normals]
    return ca.vertcat(*front, *rear, *(_heading_rows(x, p, params) if heading else ()))


def _heading_rows(x: Any, p: Any, params: VehicleParams) -> list[Any]:
    return heading_rows(x[State.d], x[State.dpsi], p[Param.curvature], p[Param.lane_lo],
                        p[Param.lane_hi], params)


def with_lane_band(p: np.ndarray, lane_lo_m: np.ndarray, lane_hi_m: np.ndarray) -> np.ndarray:
    """``p (N, N_PARAMS)`` with the heading rows' lane bounds of stages 1..N−1 from the reference
    point's bounds at stages 1..N (``(N,)`` each); stage 0's rows stay slack (its state is the
    measured one). A copy."""
    out = np.array(p, dtype=float)
    out[1:, Param.lane_lo] = np.asarray(lane_lo_m, dtype=float)[:-1]
    out[1:, Param.lane_hi] = np.asarray(lane_hi_m, dtype=float)[:-1]
    return out


def tracking_reference(
    config: PlannerConfig,
    curvature_1pm: np.ndarray,
    mu_hat: np.ndarray,
    mode: str,
    speed_mps: float,
    reference_speed_mps: float | np.ndarray,
    reference_d_m: float,
    attitude: tuple[np.ndarray, np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares reference ``yref (N+1, 9)`` over ``[x; u]`` and its weights ``(9,)``.

    Parameters
    ----------
    config
        Planner configuration (weights, horizon, ``dt``, minimal-risk deceleration).
    curvature_1pm, mu_hat
        Per stage 0..N−1 (from :func:`stage_parameters`).
    mode
        ``cruise``: track ``reference_speed_mps``; ``evade``: the same target with the light
        ``evade_speed`` weight (the caller caps it at the current speed); ``emergency``: speed 0
        with the heavy ``emergency_speed`` weight (stop short); ``minimal_risk``: a speed profile
        falling from ``speed_mps`` at ``minimal_risk_decel_fraction · μ̂_k · g`` to 0.
    speed_mps
        Current speed [m/s] (start of the minimal-risk profile).
    reference_speed_mps, reference_d_m
        Cruise speed (one value, or one per stage 0..N) and lateral offset (the lane centre)
        targets.
    attitude
        Lateral speed [m/s] and heading error [rad] targets per stage 0..N (the curve's steady
        attitude, :mod:`mufusion.planner.steady_attitude`); ``None``: zero, as in the paper.

    Returns
    -------
    yref, weights
        Weights are the diagonal of ``W`` (acados multiplies stage terms by ``dt``).
    """
    w = config.weights
    n = config.horizon_steps
    f_w = w.force_per_kn * 1e-6
    v = np.broadcast_to(np.asarray(reference_speed_mps, dtype=float), (n + 1,)).copy()
    speed_w = w.speed
    if mode == "emergency":
        speed_w, v[:] = w.emergency_speed, 0.0
    elif mode == "evade":
        speed_w = w.evade_speed
    elif mode == "minimal_risk":
        decel = config.safety.minimal_risk_decel_fraction * np.asarray(mu_hat, float) * GRAVITY_MPS2
        v[0] = max(float(speed_mps), 0.0)
        for k in range(n):
            v[k + 1] = max(v[k] - decel[k] * config.dt_s, 0.0)
    weights = np.zeros(N_STATES + N_INPUTS)
    weights[State.d] = w.lateral_offset
    weights[State.dpsi] = w.heading_error
    weights[State.psidot] = w.yaw_rate
    weights[State.vx] = speed_w
    weights[State.vy] = w.lateral_speed
    weights[N_STATES + Input.fyf] = weights[N_STATES + Input.fxf] = f_w
    weights[N_STATES + Input.fxr] = f_w
    yref = np.zeros((n + 1, N_STATES + N_INPUTS))
    yref[:, State.d] = reference_d_m
    yref[:, State.vx] = v
    kappa = np.append(curvature_1pm, curvature_1pm[-1])
    # In a curve of curvature κ the steady yaw rate is κ v.
    yref[:, State.psidot] = kappa * v
    if attitude is not None:
        yref[:, State.vy], yref[:, State.dpsi] = attitude
    return yref, weights
