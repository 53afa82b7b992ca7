"""Combined-slip tire model: pure-slip Magic Formula shapes on a friction circle of radius μ F_z.

The model is the *normalised-slip* (similarity) form of Pacejka's Magic Formula
(Pacejka, "Tire and Vehicle Dynamics", 3rd ed., Sec. 4.3): each slip component is first turned
into the force a linear tire would produce, divided by the available force μ F_z,

    s_x = K_x κ / (μ F_z) = k_x κ / μ,      s_y = K_y α / (μ F_z) = k_y α / μ,

(``k_x``, ``k_y`` = stiffness per unit load, independent of μ). Their magnitude
``λ_req = hypot(s_x, s_y)`` is the *requested utilisation*: the force the tire would need for its
slip, as a fraction of μ F_z. The delivered force magnitude is ``μ F_z Φ(λ_req)`` with the
unit-slope Magic Formula curve

    Φ(s) = sin(C atan(B s − E (B s − atan(B s)))),   B = 1 / C,

and it points along ``(s_x, s_y)``. ``Φ(λ_req)`` is the *realised utilisation* (≤ 1). Under pure
slip this is exactly the Magic Formula with peak ``D = μ F_z`` and ``B = K / (C D)`` (CommonRoad's
PAC2002 subset without its small offsets); under combined slip the force stays inside the friction
circle. C and E are blended between the longitudinal and lateral values by the direction of the
slip vector (cos² weights), so each pure-slip curve keeps its own shape.

Sign conventions (ISO-like, body frame of the wheel): κ > 0 when the wheel spins faster than it
rolls (traction), α > 0 when the wheel moves to the right of its heading, which gives a force to the
left (positive ``F_y``).

Two implementations share these equations: :func:`tire_forces` (numpy, vectorised; the public one)
and :func:`tire_forces_scalar` (plain floats, used by the plant's inner loop where numpy's per-call
overhead dominates). A test checks they agree.

Surface-dependent tires
-----------------------
Here the stiffness per unit load is fixed and only the peak scales with μ. The authors' simulator
switched the Magic Formula coefficients with the surface instead (4 /rad per unit load on snow at
μ 0.4, 22 /rad on their "wet" set at μ 0.8): :mod:`mufusion.vehicle.surface_tires` holds such
tables and turns the set at the μ under an axle into :class:`~mufusion.vehicle.params.TireParams`
for the functions here.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from mufusion.vehicle.params import TireParams

# Below this |λ_req| the direction of the slip vector is undefined; the force is linear there.
_SMALL_SLIP = 1e-12


def _blend(sx2: float, lam2: float, along_x: float, along_y: float) -> float:
    weight_x = sx2 / lam2
    return weight_x * along_x + (1.0 - weight_x) * along_y


def tire_forces_scalar(
    slip_ratio: float, slip_angle_rad: float, normal_load_n: float, mu: float, tire: TireParams
) -> tuple[float, float, float, float]:
    """Scalar version of :func:`tire_forces` (plain floats, no validation)."""
    if normal_load_n <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    sx = tire.longitudinal_stiffness_per_load * slip_ratio / mu
    sy = tire.cornering_stiffness_per_load_1_per_rad * slip_angle_rad / mu
    sx2 = sx * sx
    lam2 = sx2 + sy * sy
    if lam2 < _SMALL_SLIP * _SMALL_SLIP:
        available = mu * normal_load_n
        return available * sx, available * sy, 0.0, 0.0
    lam = math.sqrt(lam2)
    shape = _blend(sx2, lam2, tire.shape_longitudinal, tire.shape_lateral)
    curv = _blend(sx2, lam2, tire.curvature_longitudinal, tire.curvature_lateral)
    bs = lam / shape
    phi = math.sin(shape * math.atan(bs - curv * (bs - math.atan(bs))))
    scale = mu * normal_load_n * phi / lam
    return scale * sx, scale * sy, phi, lam


def tire_forces(
    slip_ratio: np.ndarray | float,
    slip_angle_rad: np.ndarray | float,
    normal_load_n: np.ndarray | float,
    mu: np.ndarray | float,
    tire: TireParams,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Combined-slip tire forces and utilisations (vectorised; arguments broadcast).

    Parameters
    ----------
    slip_ratio
        Longitudinal slip κ = (R ω − u) / |u| [-], positive under traction.
    slip_angle_rad
        Slip angle α [rad], positive when the force it produces points left.
    normal_load_n
        Normal force F_z [N]; a non-positive load (lifted wheel) gives zero force.
    mu
        Road friction coefficient under the tire [-], > 0.
    tire
        Stiffness and shape parameters.

    Returns
    -------
    fx_n, fy_n
        Longitudinal and lateral force [N] in the wheel frame.
    utilization_realised
        ``hypot(fx, fy) / (μ F_z)`` ∈ [0, 1].
    utilization_requested
        Linear-tire force for the same slip divided by μ F_z (≥ 0, may exceed 1).

    Raises
    ------
    ValueError
        If any ``mu`` is not > 0.

    Examples
    --------
    >>> from mufusion.vehicle.params import CAR
    >>> fx, fy, used, asked = tire_forces(0.0, 0.5, 4000.0, 0.5, CAR.tire)
    >>> bool(used <= 1.0 < asked)
    True
    """
    mu_arr = np.asarray(mu, dtype=float)
    if np.any(~(mu_arr > 0.0)):
        raise ValueError(f"mu must be > 0, got min {np.min(mu_arr)!r}")
    kappa, alpha, fz, mu_arr = np.broadcast_arrays(
        np.asarray(slip_ratio, dtype=float),
        np.asarray(slip_angle_rad, dtype=float),
        np.asarray(normal_load_n, dtype=float),
        mu_arr,
    )
    sx = tire.longitudinal_stiffness_per_load * kappa / mu_arr
    sy = tire.cornering_stiffness_per_load_1_per_rad * alpha / mu_arr
    lam = np.hypot(sx, sy)
    small = lam < _SMALL_SLIP
    safe_lam = np.where(small, 1.0, lam)
    weight_x = np.where(small, 0.5, sx**2 / safe_lam**2)
    shape = weight_x * tire.shape_longitudinal + (1.0 - weight_x) * tire.shape_lateral
    curv = weight_x * tire.curvature_longitudinal + (1.0 - weight_x) * tire.curvature_lateral
    bs = lam / shape
    phi = np.sin(shape * np.arctan(bs - curv * (bs - np.arctan(bs))))
    ratio = np.where(small, 1.0, phi / safe_lam)
    load = np.maximum(fz, 0.0)
    scale = mu_arr * load * ratio
    loaded = fz > 0.0
    return (
        scale * sx,
        scale * sy,
        np.where(loaded, phi, 0.0),
        np.where(loaded, lam, 0.0),
    )


@functools.lru_cache(maxsize=32)
def _peak_argument(shape: float, curvature: float) -> float:
    """``y = B s`` where ``sin(C atan(y − E (y − atan y)))`` peaks; ``inf`` where it rises for
    ever (``C ≤ 1``, or ``E = 1`` with ``π / (2C)`` out of reach)."""
    if shape <= 1.0:
        return math.inf
    target = math.tan(math.pi / (2.0 * shape))

    def inner(y: float) -> float:
        return y - curvature * (y - math.atan(y)) - target

    far = 1e6
    if inner(far) < 0.0:
        return math.inf
    from scipy.optimize import brentq  # lazily: SciPy's import is 0.4 s (docs/performance.md)

    return float(brentq(inner, 0.0, far))


def peak_slip_angle_rad(tire: TireParams, mu: float) -> float:
    """Slip angle [rad] at which the lateral force peaks on friction ``mu`` (``inf`` if it
    never does): ``y* C μ / k_y`` with ``y*`` the curve's peak argument (the normalised slip
    ``s = k_y α / μ`` peaks at ``y* / B = y* C``), so the peak moves with μ: the car's tire peaks
    at 0.142 μ rad, 1.2° on ice (μ 0.15).

    >>> from mufusion.vehicle.params import CAR
    >>> round(peak_slip_angle_rad(CAR.tire, 1.0), 3), round(peak_slip_angle_rad(CAR.tire, 0.15), 4)
    (0.142, 0.0213)
    """
    return (_peak_argument(tire.shape_lateral, tire.curvature_lateral) * tire.shape_lateral * mu
            / tire.cornering_stiffness_per_load_1_per_rad)
