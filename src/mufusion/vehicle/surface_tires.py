"""Surface-dependent tires: Magic Formula coefficient sets that change with the road friction.

The default tire of :mod:`mufusion.vehicle.tires` keeps its stiffness per unit load fixed and
scales only the peak with μ. The authors' simulator switched the Magic Formula coefficients with
the surface instead (:data:`AUTHORS_TIRES`): on snow (μ 0.4) B = 5, C = 2, so the cornering
stiffness per unit load B·C·μ is 4 /rad; on their "wet" set (μ 0.8) B = 12, C = 2.3, i.e.
22 /rad. A :class:`SurfaceTireTable` holds such sets and gives B, C, E at any μ (by μ interval,
as the authors did, or linear between anchors).

* :func:`tire_for_surface` turns the set at the μ under an axle into
  :class:`~mufusion.vehicle.params.TireParams` for :func:`~mufusion.vehicle.tires.tire_forces` and
  :func:`~mufusion.vehicle.tires.tire_forces_scalar` (peak μ F_z, lateral stiffness B·C·μ F_z),
  so a plant switches model with one argument; ``table=None`` returns the default tire.
* :func:`lateral_force_n` is the authors' per-wheel pure lateral Magic Formula.
* :func:`cornering_stiffness_per_load` is what a planner or controller assumes for an estimate μ̂
  (the authors' ``get_cornering_stiffness``), or the fixed default stiffness.

docs/estimators.md ("Surface-dependent tires") explains the physics and the CommonRoad check.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, get_args

import numpy as np

from mufusion.vehicle.params import TireParams

TireInterpolation = Literal["step", "linear"]
TIRE_INTERPOLATIONS: tuple[str, ...] = get_args(TireInterpolation)
# sup over slip of |atan(B s − E (B s − atan B s))|: π/2 if E < 1, atan(π/2) if E = 1.
_ARG_SUP_E1 = math.atan(math.pi / 2.0)


@dataclass(frozen=True)
class SurfaceTire:
    """Magic Formula coefficients of a tire on one surface; the peak is D = μ F_z.

    ``F_y = μ F_z sin(C atan(B α − E (B α − atan(B α))))`` under pure lateral slip; the cornering
    stiffness per unit load is ``B C μ``.

    Attributes
    ----------
    name : str
        Surface label, e.g. ``"snow"``.
    stiffness_factor_b_1_per_rad : float
        B [1/rad], finite and > 0.
    shape_factor_c : float
        C [-], finite and > 0; with E < 1 at most 2, with E = 1 below π / atan(π/2) ≈ 3.13, so
        the force never reverses at large slip.
    curvature_factor_e : float
        E [-], finite and ≤ 1 (E > 1 reverses the force at large slip).

    Raises
    ------
    ValueError
        If a coefficient is outside its range; the message names it.

    Examples
    --------
    >>> round(SurfaceTire("snow", 5.0, 2.0, 1.0).cornering_stiffness_per_load(0.4), 6)
    4.0
    """

    name: str
    stiffness_factor_b_1_per_rad: float
    shape_factor_c: float
    curvature_factor_e: float

    def __post_init__(self) -> None:
        where = f"SurfaceTire {self.name!r}"
        b, c, e = self.stiffness_factor_b_1_per_rad, self.shape_factor_c, self.curvature_factor_e
        if not (math.isfinite(b) and b > 0.0):
            raise ValueError(f"{where}: stiffness_factor_b_1_per_rad must be finite and > 0, "
                             f"got {b!r}")
        if not (math.isfinite(e) and e <= 1.0):
            raise ValueError(f"{where}: curvature_factor_e must be finite and ≤ 1, got {e!r}")
        c_max = 2.0 if e < 1.0 else math.pi / _ARG_SUP_E1
        if not (math.isfinite(c) and 0.0 < c <= c_max) or (e == 1.0 and c >= c_max):
            raise ValueError(f"{where}: shape_factor_c must be in (0, {c_max:.4g}] for E = {e} "
                             f"(else the force reverses at large slip), got {c!r}")

    def cornering_stiffness_per_load(self, mu: float) -> float:
        """dF_y/dα at α = 0 divided by F_z, ``B C μ`` [1/rad]."""
        return self.stiffness_factor_b_1_per_rad * self.shape_factor_c * mu


@dataclass(frozen=True)
class SurfaceTireTable:
    """Tire coefficient sets by road friction.

    Attributes
    ----------
    name : str
        Table label.
    mu_points : tuple of float
        Strictly increasing μ [-], ≥ 0, one per set. ``"step"``: set i applies for
        ``mu_points[i] ≤ μ < mu_points[i+1]`` (the first also below, the last also above);
        ``"linear"``: set i is exact at ``mu_points[i]``, B, C and E are interpolated linearly in
        between and held outside.
    sets : tuple of SurfaceTire
        The coefficient sets.
    interpolation : {"step", "linear"}
    source : str
        Where the numbers come from.

    Raises
    ------
    ValueError
        If the points are not increasing, sets and points differ in number, the interpolation is
        unknown, or a linear segment would blend E < 1 with C > 2 (a reversing curve).

    Examples
    --------
    >>> AUTHORS_TIRES.at(0.4).name, AUTHORS_TIRES.at(0.8).name
    ('snow', 'wet')
    """

    name: str
    mu_points: tuple[float, ...]
    sets: tuple[SurfaceTire, ...]
    interpolation: TireInterpolation = "step"
    source: str = ""
    # TireParams already built by tire_for_surface, by (μ, id(base)) -> (base, params): the plant
    # asks twice per step, and hashing the whole table each time would cost more than the tire.
    _params_cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "mu_points", tuple(float(m) for m in self.mu_points))
        object.__setattr__(self, "sets", tuple(self.sets))
        where = f"SurfaceTireTable {self.name!r}"
        points = np.array(self.mu_points)
        if points.size == 0 or len(self.sets) != points.size:
            raise ValueError(f"{where}: need one mu_point per set and at least one, got "
                             f"{points.size} points and {len(self.sets)} sets")
        if not (np.all(np.isfinite(points)) and points[0] >= 0.0 and np.all(np.diff(points) > 0)):
            raise ValueError(f"{where}: mu_points must be finite, ≥ 0 and strictly increasing, "
                             f"got {self.mu_points}")
        if any(not isinstance(t, SurfaceTire) for t in self.sets):
            raise ValueError(f"{where}: sets must hold SurfaceTire instances")
        if self.interpolation not in TIRE_INTERPOLATIONS:
            raise ValueError(f"{where}: interpolation must be one of {list(TIRE_INTERPOLATIONS)}, "
                             f"got {self.interpolation!r}")
        if self.interpolation == "linear":
            for a, b in zip(self.sets[:-1], self.sets[1:], strict=True):
                blended_e_below_1 = min(a.curvature_factor_e, b.curvature_factor_e) < 1.0
                if blended_e_below_1 and max(a.shape_factor_c, b.shape_factor_c) > 2.0:
                    raise ValueError(f"{where}: between {a.name!r} and {b.name!r} a blend has "
                                     "E < 1 and C > 2, whose force reverses at large slip")

    def coefficients(self, mu: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """B [1/rad], C and E at each ``mu`` (arrays of the shape of ``mu``)."""
        mu = np.asarray(mu, dtype=float)
        b = np.array([t.stiffness_factor_b_1_per_rad for t in self.sets])
        c = np.array([t.shape_factor_c for t in self.sets])
        e = np.array([t.curvature_factor_e for t in self.sets])
        if self.interpolation == "linear":
            points = np.array(self.mu_points)
            return np.interp(mu, points, b), np.interp(mu, points, c), np.interp(mu, points, e)
        index = np.searchsorted(self.mu_points, mu, side="right") - 1
        index = np.clip(index, 0, len(self.sets) - 1)
        return b[index], c[index], e[index]

    def at(self, mu: float) -> SurfaceTire:
        """The coefficient set at one ``mu`` (named after the nearest set at or below it)."""
        b, c, e = (float(v) for v in self.coefficients(mu))
        below = int(np.clip(np.searchsorted(self.mu_points, mu, side="right") - 1, 0, None))
        return SurfaceTire(self.sets[below].name, b, c, e)


# Authors' simulator, tamp_ws common/scripts/exp_manager.py get_tire_params(mu): one set per
# friction interval, switched with the μ under the vehicle (their planner's get_cornering_stiffness
# uses the same sets up to 1.5).
AUTHORS_TIRES = SurfaceTireTable(
    name="authors",
    mu_points=(0.0, 0.3, 0.5, 0.9, 1.5),
    sets=(
        SurfaceTire("ice", 4.0, 2.0, 1.0),
        SurfaceTire("snow", 5.0, 2.0, 1.0),
        SurfaceTire("wet", 12.0, 2.3, 1.0),
        SurfaceTire("dry", 10.0, 1.9, 0.97),
        SurfaceTire("dry-racing", 12.56, 1.38, 1.0),
    ),
    interpolation="step",
    source="Svensson's tamp_ws exp_manager.get_tire_params: ice [0, 0.3), snow [0.3, 0.5), "
    "wet [0.5, 0.9), dry [0.9, 1.5), dry with racing tires [1.5, 2.5)",
)

# The same sets without jumps: exact at ice's class centre and the turn scenario's two surfaces
# (0.4, 0.8), linear in between, held outside. The dry set is left out: blending it with the wet
# one (E 0.97 with C 2.3) gives a curve that reverses at large slip.
AUTHORS_TIRES_INTERPOLATED = SurfaceTireTable(
    name="authors-interpolated",
    mu_points=(0.15, 0.4, 0.8),
    sets=AUTHORS_TIRES.sets[:3],
    interpolation="linear",
    source="the authors' ice, snow and wet sets anchored at μ 0.15, 0.4 and 0.8",
)

TIRE_TABLES: dict[str, SurfaceTireTable] = {
    "authors": AUTHORS_TIRES,
    "authors-interpolated": AUTHORS_TIRES_INTERPOLATED,
}


def tire_table(name: str) -> SurfaceTireTable:
    """Return a surface-dependent tire table by name.

    Parameters
    ----------
    name : {"authors", "authors-interpolated"}

    Raises
    ------
    ValueError
        If ``name`` is unknown; the message lists the tables.

    Examples
    --------
    >>> tire_table("authors").at(0.89).name
    'wet'
    """
    try:
        return TIRE_TABLES[name]
    except KeyError:
        raise ValueError(f"tire table must be one of {sorted(TIRE_TABLES)}, got {name!r}") from None


# Bound on the cache of built TireParams per table (μ takes few values in a scenario).
_CACHE_SIZE = 4096


def _surface_params(mu: float, base: TireParams, table: SurfaceTireTable) -> TireParams:
    b, c, e = (float(v) for v in table.coefficients(mu))
    return TireParams(
        cornering_stiffness_per_load_1_per_rad=b * c * mu,
        # No longitudinal data in the tables: the base tire's slip stiffness, and the surface's
        # curve shape in every direction so that a combined-slip blend cannot reverse the force.
        longitudinal_stiffness_per_load=base.longitudinal_stiffness_per_load,
        shape_lateral=c,
        shape_longitudinal=c,
        curvature_lateral=e,
        curvature_longitudinal=e,
        source=f"{table.name} at mu={mu:g}",
    )


def tire_for_surface(
    mu: float, base: TireParams, table: SurfaceTireTable | None = None
) -> TireParams:
    """Tire parameters for the combined-slip model on a surface of friction ``mu``.

    Parameters
    ----------
    mu : float
        Road friction under the axle [-], finite and > 0.
    base : TireParams
        The vehicle's tire (its longitudinal stiffness is kept).
    table : SurfaceTireTable, optional
        None: ``base`` itself (the default model, stiffness independent of μ). Otherwise lateral
        stiffness per unit load ``B C μ`` with the table's B, C, E at ``mu``, and that C, E for
        the curve in every slip direction.

    Returns
    -------
    TireParams
        For :func:`tire_forces` / :func:`tire_forces_scalar` with the same ``mu``: pure lateral
        slip then gives exactly ``μ F_z sin(C atan(B α − E (B α − atan B α)))``.

    Raises
    ------
    ValueError
        If ``mu`` is not finite and > 0.

    Examples
    --------
    >>> from mufusion.vehicle.params import TRUCK
    >>> wet = tire_for_surface(0.8, TRUCK.tire, AUTHORS_TIRES)
    >>> round(wet.cornering_stiffness_per_load_1_per_rad, 2), wet.shape_lateral
    (22.08, 2.3)
    """
    mu = float(mu)
    if not (math.isfinite(mu) and mu > 0.0):
        raise ValueError(f"mu must be finite and > 0, got {mu!r}")
    if table is None:
        return base
    cache = table._params_cache
    hit = cache.get((mu, id(base)))
    if hit is not None and hit[0] is base:
        return hit[1]
    params = _surface_params(mu, base, table)
    if len(cache) >= _CACHE_SIZE:
        cache.clear()
    cache[(mu, id(base))] = (base, params)
    return params


def cornering_stiffness_per_load(
    mu: np.ndarray | float, base: TireParams, table: SurfaceTireTable | None = None
) -> np.ndarray:
    """Cornering stiffness per unit normal load [1/rad] a model assumes for friction ``mu``.

    What the authors' planner and controller computed from the estimate μ̂
    (``get_cornering_stiffness(mu, Fz) = B C μ F_z``); multiply by F_z for N/rad.

    Parameters
    ----------
    mu : array_like
        Friction coefficient(s) [-] (e.g. μ̂ per planner stage), finite and > 0.
    base : TireParams
        Used when ``table`` is None: its μ-independent stiffness.
    table : SurfaceTireTable, optional

    Returns
    -------
    numpy.ndarray
        Shape of ``mu``.

    Raises
    ------
    ValueError
        If any ``mu`` is not finite and > 0.

    Examples
    --------
    >>> from mufusion.vehicle.params import TRUCK
    >>> cornering_stiffness_per_load([0.4, 0.8], TRUCK.tire, AUTHORS_TIRES).round(2).tolist()
    [4.0, 22.08]
    >>> cornering_stiffness_per_load([0.4, 0.8], TRUCK.tire).tolist()
    [7.0, 7.0]
    """
    mu = np.asarray(mu, dtype=float)
    if not np.all(np.isfinite(mu) & (mu > 0.0)):
        raise ValueError("mu must be finite and > 0 everywhere")
    if table is None:
        return np.full(mu.shape, base.cornering_stiffness_per_load_1_per_rad)
    b, c, _ = table.coefficients(mu)
    return b * c * mu


def lateral_force_n(
    slip_angle_rad: np.ndarray | float,
    normal_load_n: np.ndarray | float,
    mu: np.ndarray | float,
    table: SurfaceTireTable,
) -> np.ndarray:
    """Pure-slip lateral force of a surface-dependent tire (the authors' per-wheel model).

    ``F_y = μ F_z sin(C atan(B α − E (B α − atan B α)))`` with B, C, E from ``table`` at ``mu``;
    arguments broadcast; a non-positive load gives 0.

    Raises
    ------
    ValueError
        If any ``mu`` is not finite and > 0.

    Examples
    --------
    >>> round(float(lateral_force_n(0.311, 1000.0, 0.4, AUTHORS_TIRES)), 1)  # snow's peak
    400.0
    """
    mu = np.asarray(mu, dtype=float)
    if not np.all(np.isfinite(mu) & (mu > 0.0)):
        raise ValueError("mu must be finite and > 0 everywhere")
    b, c, e = table.coefficients(mu)
    x = b * np.asarray(slip_angle_rad, dtype=float)
    return mu * np.maximum(normal_load_n, 0.0) * np.sin(c * np.arctan(x - e * (x - np.arctan(x))))
