"""Tracking controller: turns the current plan into actuator commands at ≥ 50 Hz.

Steering = inverse Magic-Formula of the planned front lateral force at the planned normal load and
friction estimate (with the tire the planner assumes: the vehicle's own, or with
``PlannerConfig.stiffness = "from_mu_hat"`` the set of its ``stiffness_table`` at μ̂), plus
the small-angle slip kinematics ``δ = α_f + (v_y + l_f ψ̇)/v_x``, plus feedback on lateral and
heading error. Wheel torques = planned longitudinal forces × wheel radius, plus speed feedback,
compensating the torques' first-order lag (``ControllerGains.torque_compensation``): the forces are
read one torque time constant ahead in the plan, and the measured torque's shortfall against the
plan of now is removed within one controller period.
The command is rate-limited and clipped to the actuators' ranges.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from mufusion.planner.planner import Plan
from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import TireParams, VehicleParams
from mufusion.vehicle.planner_model import MIN_SPEED_FOR_SLIP_MPS, Input, State
from mufusion.vehicle.surface_tires import tire_for_surface


@dataclass(frozen=True)
class ControllerGains:
    """Feedback gains (named, SI units)."""

    lateral_rad_per_m: float = 0.05
    heading_rad_per_rad: float = 0.6
    yaw_rate_rad_per_radps: float = 0.15
    steer_preview_s: float = 0.2
    speed_1_per_s: float = 0.8
    rate_hz: float = 50.0
    torque_compensation: bool = True
    """Compensate the wheel torques' first-order lag τ (``VehicleParams.torque_time_constant_s``,
    0.15 s for the truck), which otherwise delivers every planned brake application late.
    Feed-forward: the longitudinal forces the plan asks for τ ahead (a first-order lag follows a
    ramp τ behind). Feedback, given the measured torques: their shortfall against the plan of now
    (a new plan's first stage, which no feed-forward could anticipate), removed within one
    controller period (dead-beat for the lag: gain ``e/(1 − e)``, ``e = exp(−h/τ)``).
    ``False``: the forces planned for now, as in the paper's controller. With
    ``PlannerConfig.torque_lag`` the plan's forces already follow the lag: the stage's commands
    are sent either way, and the feedback (``True``) is onto the plan's forces one controller
    period ahead."""


def _magic_formula_lateral(alpha: np.ndarray, fz: float, mu: float, tire: TireParams):
    c, e = tire.shape_lateral, tire.curvature_lateral
    d = mu * fz
    b = tire.cornering_stiffness_per_load_1_per_rad * fz / (c * d)
    ba = b * alpha
    return d * np.sin(c * np.arctan(ba - e * (ba - np.arctan(ba))))


def front_slip_angle_for_force_rad(
    force_n: float, normal_load_n: float, mu_hat: float, tire: TireParams
) -> float:
    """Slip angle [rad] at which the lateral Magic Formula gives ``force_n`` (saturated at peak).

    Stiffness ``cornering_stiffness_per_load × F_z``, peak ``μ̂ F_z`` (TireParams' convention).
    """
    fz, mu = max(normal_load_n, 1.0), max(mu_hat, 0.05)
    force, alpha = _rising_branch(fz, mu, tire)
    magnitude = float(np.interp(abs(force_n), force, alpha))
    return float(np.sign(force_n)) * magnitude


@functools.lru_cache(maxsize=64)
def _rising_branch(fz: float, mu: float, tire: TireParams) -> tuple[np.ndarray, np.ndarray]:
    """Tabulated force and slip angle up to the peak, at one load, friction and tire.

    Cached: the controller previews one plan stage for several ticks in a row, so the same
    (load, μ̂) comes back until the plan's next stage or the next plan.
    """
    c = tire.shape_lateral
    b = tire.cornering_stiffness_per_load_1_per_rad / (c * mu)
    # The force rises monotonically up to the peak at C·atan(...) = π/2; tabulate up to there.
    alpha = np.linspace(0.0, 3.0 / b, 400)
    force = _magic_formula_lateral(alpha, fz, mu, tire)
    peak = int(np.argmax(force))
    force, alpha = force[: peak + 1], alpha[: peak + 1]
    force.flags.writeable = alpha.flags.writeable = False
    return force, alpha


def _interpolate(states: np.ndarray, k: int, frac: float) -> list[float]:
    """``(1 − frac) · states[k] + frac · states[k + 1]`` as floats."""
    weight = 1.0 - frac
    return [weight * a + frac * b for a, b in zip(states[k].tolist(), states[k + 1].tolist(),
                                                  strict=True)]


class TrackingController:
    """Feed-forward + feedback plan tracker.

    Its only state is the last steering command: the command signal is rate-limited against it.
    Limiting against the *measured* steering angle instead would compound with the servo's lag
    and cut the usable steering rate to a fraction of the actuator's (≈ 1/3 for the truck).
    """

    def __init__(self, params: VehicleParams, config=None, gains: ControllerGains | None = None):
        self.params = params
        self.config = config
        self.gains = gains or ControllerGains()
        if self.gains.rate_hz < 50.0:
            raise ValueError(f"rate_hz must be >= 50 Hz, got {self.gains.rate_hz}")
        # Fixed by the vehicle and the rate: computed once, not at every tick.
        self._torque_gain = _dead_beat_gain(1.0 / self.gains.rate_hz,
                                            params.torque_time_constant_s)
        self._last_steer_cmd_rad: float | None = None

    def _assumed_tire(self, mu_hat: float) -> TireParams:
        """The front tire the feed-forward inverts: the vehicle's, or the table's set at μ̂."""
        table = None if self.config is None else self.config.stiffness_table
        if table is None or not (mu_hat > 0.0 and np.isfinite(mu_hat)):
            return self.params.tire
        # front_slip_angle_for_force_rad floors μ̂ at 0.05; the tire follows the same value.
        return tire_for_surface(max(mu_hat, 0.05), self.params.tire, table)

    def reset(self) -> None:
        """Forget the last steering command (the next one is limited against the measured angle)."""
        self._last_steer_cmd_rad = None

    def command(
        self,
        t_s: float,
        x_frenet: np.ndarray,
        steer_rad_now: float,
        plan: Plan,
        curvature_1pm_now: float = 0.0,
        torques_now_nm: tuple[float, float] | None = None,
    ) -> ActuatorCommand:
        """Actuator command at time ``t_s`` [s] for the Frenet state ``x_frenet`` (6,).

        ``torques_now_nm``: the measured (front, rear) wheel torques [N m] for the torque lag's
        feedback (``None`` or not finite: feed-forward only)."""
        par, g = self.params, self.gains
        # Plain floats from here on (the same IEEE arithmetic as numpy's, element by element,
        # without its per-operation overhead at the controller's rate).
        x = np.asarray(x_frenet, dtype=float).tolist()
        n = plan.inputs.shape[0]
        # min/max: np.clip's values on plain floats.
        tau = float(min(max((t_s - plan.t0_s) / plan.dt_s, 0.0), n - 1e-9))
        k = int(tau)
        x_ref = _interpolate(plan.states, k, tau - k)
        u = plan.inputs[k].tolist()
        # The longitudinal forces are read ahead by the torque lag (see ControllerGains).
        u_long = (plan.inputs[int(min(tau + par.torque_time_constant_s / plan.dt_s, n - 1e-9))]
                  .tolist() if g.torque_compensation else u)
        if not (all(map(math.isfinite, x)) and all(map(math.isfinite, x_ref))
                and all(map(math.isfinite, u)) and all(map(math.isfinite, u_long))):
            # Degrade, never raise: hold the wheel and brake gently.
            brake = -0.1 * par.mass_kg * 9.81 * par.wheel_radius_m
            return ActuatorCommand(float(steer_rad_now), 0.5 * brake, 0.5 * brake).clipped(par)

        vx = max(x[State.vx], MIN_SPEED_FOR_SLIP_MPS)
        # The feed-forward previews the plan by the steering's lag: a planned reversal of the
        # front force (counter-steer) must start before the plan's stage does.
        tau_p = min(max(tau + g.steer_preview_s / plan.dt_s, 0.0), n - 1e-9)
        k_p = int(tau_p)
        x_p = _interpolate(plan.states, k_p, tau_p - k_p)
        mu_p = float(plan.mu_hat[k_p])
        alpha_f = front_slip_angle_for_force_rad(
            float(plan.inputs[k_p, Input.fyf]), float(plan.normal_load_front_n[k_p]), mu_p,
            self._assumed_tire(mu_p),
        )
        vx_ref = max(x_p[State.vx], MIN_SPEED_FOR_SLIP_MPS)
        # α_f = δ − (v_y + l_f ψ̇)/v_x, solved for δ.
        kinematic = x_p[State.vy] + par.cog_to_front_axle_m * x_p[State.psidot]
        delta_ff = alpha_f + kinematic / vx_ref
        # Left positive: a lateral offset to the right of the plan steers left.
        delta_fb = g.lateral_rad_per_m * (x_ref[State.d] - x[State.d]) + g.heading_rad_per_rad * (
            x_ref[State.dpsi] - x[State.dpsi]
        )
        # Yaw-rate feedback damps what the plan cannot see: a rear tire that saturates before the
        # planner's linear rear tire says it would (over-rotation, the start of a spin).
        delta_fb += g.yaw_rate_rad_per_radps * (x_ref[State.psidot] - x[State.psidot])
        delta = delta_ff + delta_fb
        max_step = par.max_steer_rate_radps / g.rate_hz
        prev = steer_rad_now if self._last_steer_cmd_rad is None else self._last_steer_cmd_rad
        delta = float(min(max(delta, prev - max_step), prev + max_step))
        delta = min(max(delta, -par.max_steer_rad), par.max_steer_rad)
        self._last_steer_cmd_rad = delta

        extra_force = par.mass_kg * g.speed_1_per_s * (x_ref[State.vx] - vx)
        if extra_force >= 0.0:
            extra_f, extra_r = 0.0, extra_force
        else:
            share_front = par.cog_to_rear_axle_m / par.wheelbase_m
            extra_f, extra_r = share_front * extra_force, (1.0 - share_front) * extra_force
        r = par.wheel_radius_m
        measured = (g.torque_compensation and torques_now_nm is not None
                    and all(map(math.isfinite, torques_now_nm)))
        if self.config is not None and self.config.torque_lag:
            # The plan's forces follow the lag already (planner/ocp_state.py): its commands of
            # the stage are the torques to send; with the compensation and a measurement, the
            # torques go where the plan has them one controller period ahead (dead-beat).
            period = 1.0 / g.rate_hz
            if measured:
                assert torques_now_nm is not None
                target = lagged_forces_n(plan, t_s + period, par.torque_time_constant_s)
                gain = self._torque_gain
                torque_f = (target[0] + extra_f) * r
                torque_r = (target[1] + extra_r) * r
                torque_f += gain * (torque_f - torques_now_nm[0])
                torque_r += gain * (torque_r - torques_now_nm[1])
            else:
                commands = stage_commands_n(plan, k, par.torque_time_constant_s)
                torque_f = (commands[0] + extra_f) * r
                torque_r = (commands[1] + extra_r) * r
            return ActuatorCommand(delta, torque_f, torque_r).clipped(par)
        torque_f = (float(u_long[Input.fxf]) + extra_f) * r
        torque_r = (float(u_long[Input.fxr]) + extra_r) * r
        # A measurement that is not finite is not fed back (feed-forward only).
        if measured:
            assert torques_now_nm is not None
            gain = self._torque_gain
            torque_f += gain * ((float(u[Input.fxf]) + extra_f) * r - torques_now_nm[0])
            torque_r += gain * ((float(u[Input.fxr]) + extra_r) * r - torques_now_nm[1])
        return ActuatorCommand(delta, torque_f, torque_r).clipped(par)


def stage_commands_n(plan: Plan, k: int, tau_s: float) -> tuple[float, float]:
    """The longitudinal force commands ``(F_xf, F_xr)`` [N] of a plan's stage ``k`` whose forces
    follow a first-order lag of time constant ``tau_s`` (``PlannerConfig.torque_lag``): the
    commands that carry stage k's forces to stage k+1's, ``(F_{k+1} − e F_k) / (1 − e)`` with
    ``e = exp(−dt/τ)``; the last stage holds its forces."""
    n = plan.inputs.shape[0]
    now = plan.inputs[k]
    if k + 1 >= n:
        return float(now[Input.fxf]), float(now[Input.fxr])
    nxt = plan.inputs[k + 1]
    e = math.exp(-plan.dt_s / tau_s)
    return ((float(nxt[Input.fxf]) - e * float(now[Input.fxf])) / (1.0 - e),
            (float(nxt[Input.fxr]) - e * float(now[Input.fxr])) / (1.0 - e))


def lagged_forces_n(plan: Plan, t_s: float, tau_s: float) -> tuple[float, float]:
    """The longitudinal forces ``(F_xf, F_xr)`` [N] a plan whose forces follow the lag has at
    ``t_s``: within stage k, ``u + (F_k − u) exp(−σ/τ)`` with the stage's commands ``u``
    (:func:`stage_commands_n`) and ``σ`` the time since the stage's start."""
    n = plan.inputs.shape[0]
    tau = float(min(max((t_s - plan.t0_s) / plan.dt_s, 0.0), n - 1e-9))
    k = int(tau)
    decay = math.exp(-(tau - k) * plan.dt_s / tau_s)
    u_f, u_r = stage_commands_n(plan, k, tau_s)
    now = plan.inputs[k]
    return (u_f + (float(now[Input.fxf]) - u_f) * decay,
            u_r + (float(now[Input.fxr]) - u_r) * decay)


def _dead_beat_gain(period_s: float, tau_s: float) -> float:
    """Feedback gain that closes a first-order lag's error in one period of held command.

    Over ``period_s`` the lag moves ``T`` to ``u + (T − u) e`` with ``e = exp(−period/τ)``; the
    command ``T* + K (T* − T)`` lands on ``T*`` for ``K = e / (1 − e)`` (6.99 for the truck at
    50 Hz).
    """
    e = math.exp(-period_s / tau_s)
    return e / (1.0 - e)
