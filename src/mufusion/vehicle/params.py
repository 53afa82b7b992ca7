"""Vehicle parameter sets: frozen data with SI units in every field name and a source per preset.

Each number is defined once, here. The planner's model, the plant and the controller all read the
same :class:`VehicleParams`, so they cannot drift apart by copy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

GRAVITY_MPS2 = 9.81


@dataclass(frozen=True)
class TireParams:
    """Magic Formula shape parameters, normalised by the normal load.

    The peak force of a tire is ``mu * F_z`` (``mu`` = road friction under that axle); its
    stiffness near zero slip is ``stiffness_per_load * F_z`` and does not depend on ``mu``, so the
    Magic Formula's B follows as ``B = stiffness / (C * mu * F_z)`` (as CommonRoad's STD model does
    when its peak factor is scaled by the road friction).

    Attributes
    ----------
    cornering_stiffness_per_load_1_per_rad
        Lateral stiffness dF_y/dα at α = 0 divided by F_z [1/rad].
    longitudinal_stiffness_per_load
        Longitudinal stiffness dF_x/dκ at κ = 0 divided by F_z [-].
    shape_lateral, shape_longitudinal
        Magic Formula C (shape) factors [-].
    curvature_lateral, curvature_longitudinal
        Magic Formula E (curvature) factors [-].
    """

    cornering_stiffness_per_load_1_per_rad: float
    longitudinal_stiffness_per_load: float
    shape_lateral: float = 1.9
    shape_longitudinal: float = 1.65
    curvature_lateral: float = 0.97
    curvature_longitudinal: float = 0.0
    source: str = ""


@dataclass(frozen=True)
class VehicleParams:
    """Rigid-body, geometry, tire and actuator parameters of one vehicle (SI units).

    Raises
    ------
    ValueError
        If a field is not finite or outside its physical range; the message names the field.
    """

    name: str
    mass_kg: float
    yaw_inertia_kgm2: float
    cog_to_front_axle_m: float
    cog_to_rear_axle_m: float
    cog_height_m: float
    width_m: float
    length_m: float
    track_width_m: float
    wheel_radius_m: float
    wheel_inertia_kgm2: float
    max_steer_rad: float
    max_steer_rate_radps: float
    max_drive_torque_nm: float
    max_brake_torque_front_nm: float
    max_brake_torque_rear_nm: float
    tire: TireParams
    # Actuator lags of the plant: first-order steering servo (also rate-limited by
    # ``max_steer_rate_radps``) and first-order wheel-torque build-up. The planner's model has
    # neither; the controller compensates them (planner/controller.py).
    steer_time_constant_s: float = 0.05
    torque_time_constant_s: float = 0.1
    source: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, float | int) and not isinstance(value, bool):
                if not math.isfinite(value) or value <= 0.0:
                    raise ValueError(
                        f"VehicleParams.{f.name} must be a finite number > 0, got {value!r}"
                    )
        for f in fields(self.tire):
            value = getattr(self.tire, f.name)
            if f.name.startswith(("cornering", "longitudinal_stiffness", "shape")) and (
                not math.isfinite(value) or value <= 0.0
            ):
                raise ValueError(f"TireParams.{f.name} must be a finite number > 0, got {value!r}")
        for name in ("shape_lateral", "shape_longitudinal"):
            # C ≥ 2 would let the Magic Formula change sign at large slip.
            value = getattr(self.tire, name)
            if not value < 2.0:
                raise ValueError(f"TireParams.{name} must be in (0, 2), got {value!r}")
        for name in ("curvature_lateral", "curvature_longitudinal"):
            value = getattr(self.tire, name)
            if not (math.isfinite(value) and value <= 1.0):
                raise ValueError(f"TireParams.{name} must be finite and <= 1, got {value!r}")

    @property
    def wheelbase_m(self) -> float:
        """Distance between the axles [m]."""
        return self.cog_to_front_axle_m + self.cog_to_rear_axle_m

    @property
    def body_centre_ahead_of_cog_m(self) -> float:
        """How far the body's centre lies ahead of the CoG [m] (negative: behind it).

        The footprint is the ``length × width`` rectangle centred midway between the axles."""
        return 0.5 * (self.cog_to_front_axle_m - self.cog_to_rear_axle_m)

    @property
    def cog_to_body_front_m(self) -> float:
        """Distance from the CoG to the footprint's front edge [m]."""
        return 0.5 * self.length_m + self.body_centre_ahead_of_cog_m

    @property
    def cog_to_body_rear_m(self) -> float:
        """Distance from the CoG to the footprint's rear edge [m]."""
        return 0.5 * self.length_m - self.body_centre_ahead_of_cog_m

    @property
    def static_front_load_n(self) -> float:
        """Static normal force on the front axle [N]."""
        return self.mass_kg * GRAVITY_MPS2 * self.cog_to_rear_axle_m / self.wheelbase_m

    @property
    def static_rear_load_n(self) -> float:
        """Static normal force on the rear axle [N]."""
        return self.mass_kg * GRAVITY_MPS2 * self.cog_to_front_axle_m / self.wheelbase_m


def _rectangle_yaw_inertia_kgm2(mass_kg: float, length_m: float, width_m: float) -> float:
    # Uniform rectangular plate about its centre: I = m (l² + w²) / 12.
    return mass_kg * (length_m**2 + width_m**2) / 12.0


_TRUCK_MASS_KG = 8350.0
_TRUCK_WHEELBASE_M = 3.4
# Axle loads 5,375 kg front / 2,960 kg rear place the CoG at l_f = L · m_r / (m_f + m_r).
_TRUCK_LF_M = _TRUCK_WHEELBASE_M * 2960.0 / (5375.0 + 2960.0)

TRUCK = VehicleParams(
    name="truck",
    mass_kg=_TRUCK_MASS_KG,
    yaw_inertia_kgm2=_rectangle_yaw_inertia_kgm2(_TRUCK_MASS_KG, 6.28, 2.6),
    cog_to_front_axle_m=_TRUCK_LF_M,
    cog_to_rear_axle_m=_TRUCK_WHEELBASE_M - _TRUCK_LF_M,
    cog_height_m=1.0,
    width_m=2.6,
    length_m=6.28,
    track_width_m=2.0,
    wheel_radius_m=0.5,
    # Twin wheels per axle side, ~20 kg m² per rear axle end incl. brake drums and driveline.
    wheel_inertia_kgm2=40.0,
    max_steer_rad=0.6,
    # Road-wheel rate of an automated steering actuator (≈ 50°/s; a 20:1 gear needs ≈ 1,000°/s at
    # the hand wheel, an emergency human input). At 0.6 rad/s the planner's evasive plans, which
    # have no steering-rate model, cannot be tracked and the truck spins (docs/planner.md).
    max_steer_rate_radps=0.9,
    max_drive_torque_nm=25_000.0,
    max_brake_torque_front_nm=40_000.0,
    max_brake_torque_rear_nm=30_000.0,
    # Pneumatic brakes build up torque in ≈ 0.2-0.3 s; a 0.15 s lag stands for brake and drive.
    torque_time_constant_s=0.15,
    tire=TireParams(
        # Truck tires: cornering coefficient ≈ 7/rad, longitudinal ≈ 12 (heavy-vehicle tire data,
        # Pacejka "Tire and Vehicle Dynamics" ch. 4; Wong "Theory of Ground Vehicles" Tab. 1.5).
        cornering_stiffness_per_load_1_per_rad=7.0,
        longitudinal_stiffness_per_load=12.0,
        shape_lateral=1.9,
        shape_longitudinal=1.65,
        curvature_lateral=0.97,
        curvature_longitudinal=0.0,
        source="typical heavy-truck tire coefficients; shape factors after Pacejka (2012)",
    ),
    source=(
        "Volvo FH16 tractor as in Svensson & Törngren's TAMP set-up: mass, axle loads, wheelbase, "
        "CoG height, width, length, track and wheel radius; yaw inertia by the rectangle "
        "approximation m(l² + w²)/12"
    ),
)

# CommonRoad vehicle parameter set 2 (BMW 320i), commonroad-vehicle-models 3.0.2,
# `parameters_vehicle2()`: m, a, b, I_z, h_cg, w, l, R_w, I_y_w, steering limits and the PAC2002
# pure-slip tire coefficients (p_ky1, p_kx1, p_cy1, p_cx1, p_ey1, p_ex1). The track is the mean of
# T_f and T_r. The peak factors p_dy1 ≈ 1.05, p_dx1 ≈ 1.17 are not copied: here the peak is μ F_z.
CAR = VehicleParams(
    name="car",
    mass_kg=1093.2952334674046,
    yaw_inertia_kgm2=1791.5995300122856,
    cog_to_front_axle_m=1.1561957064,
    cog_to_rear_axle_m=1.4227170936,
    cog_height_m=0.5748689544,
    width_m=1.61,
    length_m=4.508,
    track_width_m=0.5 * (1.38684 + 1.36398),
    wheel_radius_m=0.344,
    wheel_inertia_kgm2=1.7,
    max_steer_rad=1.066,
    max_steer_rate_radps=0.4,
    # Hydraulic brakes and the 11.5 m/s² CommonRoad acceleration limit (m R_w a ≈ 4.3 kN m).
    max_drive_torque_nm=3_000.0,
    max_brake_torque_front_nm=4_000.0,
    max_brake_torque_rear_nm=2_500.0,
    torque_time_constant_s=0.05,
    tire=TireParams(
        cornering_stiffness_per_load_1_per_rad=21.92,
        longitudinal_stiffness_per_load=22.303,
        shape_lateral=1.3507,
        shape_longitudinal=1.6411,
        curvature_lateral=-0.0074722,
        curvature_longitudinal=0.46403,
        source="CommonRoad parameters_vehicle2 PAC2002: |p_ky1|, p_kx1, p_cy1, p_cx1, p_ey1, p_ex1",
    ),
    source="CommonRoad vehicle models 3.0.2, parameter set 2 (BMW 320i)",
)

PRESETS: dict[str, VehicleParams] = {"truck": TRUCK, "car": CAR}


def vehicle_preset(name: str) -> VehicleParams:
    """Return a vehicle parameter preset by name.

    Parameters
    ----------
    name
        ``"truck"`` (Volvo FH16-like tractor) or ``"car"`` (CommonRoad BMW 320i).

    Raises
    ------
    ValueError
        If ``name`` is not a known preset; the message lists the allowed names.

    Examples
    --------
    >>> round(vehicle_preset("truck").wheelbase_m, 3)
    3.4
    """
    try:
        return PRESETS[name]
    except KeyError:
        raise ValueError(
            f"vehicle must be one of {sorted(PRESETS)}, got {name!r}"
        ) from None
