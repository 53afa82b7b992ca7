"""Graded outcomes of a run, read from its log: how far out, how close, how hard the tires worked.

A yes/no verdict ("left its lane") hides whether a corner grazed the line by a centimetre or the
truck slid across the opposing lane. :func:`graded_outcome` measures it: the farthest footprint
corner beyond the ego lane's edge (the road is rebuilt from the run's validated scenario and the
footprint is placed as the loop places it), the centre's largest offset, the obstacle clearance
or impact speed, and the realised front-tire utilisation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mufusion.road import rectangle_corners
from mufusion.scenarios.loading import scenario_from_dict
from mufusion.sim.log import RunLog
from mufusion.vehicle.params import vehicle_preset

SATURATION = 0.98
"""Realised utilisation at which a tire counts as saturated (sliding) [-]."""


@dataclass(frozen=True)
class GradedOutcome:
    """Graded outcome of one run.

    Attributes
    ----------
    max_abs_offset_m
        Largest ``|d|`` of the centre of gravity from the lane centre.
    lane_excursion_m
        Largest distance of a footprint corner beyond the ego lane's edges (either side);
        negative: the smallest room left inside the lane.
    left_lane, entered_opposing_lane, collision
        The yes/no outcomes (as the loop recorded them).
    impact_speed_mps, min_clearance_m
        Speed at the first contact, or the smallest clearance while passing (``None``: none).
    peak_util_front
        Largest realised front-tire utilisation; ``saturated`` if it reached
        :data:`SATURATION`.
    """

    max_abs_offset_m: float
    lane_excursion_m: float
    left_lane: bool
    entered_opposing_lane: bool
    collision: bool
    impact_speed_mps: float | None
    min_clearance_m: float | None
    peak_util_front: float

    @property
    def saturated(self) -> bool:
        return self.peak_util_front >= SATURATION


def corner_offsets_m(log: RunLog) -> np.ndarray:
    """Lateral offsets ``d`` of the four footprint corners at every tick, shape ``(T, 4)``.

    Raises
    ------
    ValueError
        If the run's scenario in its metadata no longer validates.
    """
    meta = log.meta
    cfg = scenario_from_dict(dict(meta.scenario_config), "the run's metadata")
    params = vehicle_preset(cfg.vehicle)
    road = cfg.build_road(params)
    ts = log.timeseries
    psi = ts["psi_rad"].to_numpy(dtype=float)
    # The footprint is centred between its ends, ahead of the CoG by this much (as in the loop).
    shift = 0.5 * (meta.vehicle.cog_to_front_axle_m - meta.vehicle.cog_to_rear_axle_m)
    cx = ts["x_m"].to_numpy(dtype=float) + shift * np.cos(psi)
    cy = ts["y_m"].to_numpy(dtype=float) + shift * np.sin(psi)
    corners = rectangle_corners(cx, cy, psi, meta.vehicle.length_m, meta.vehicle.width_m)
    _, d, _ = road.path.to_frenet(corners[..., 0], corners[..., 1])
    return d


def lane_excursion_m(log: RunLog) -> float:
    """Largest distance [m] of a footprint corner beyond the ego lane's edges (negative: inside).

    Examples
    --------
    A run that keeps every corner 0.1 m inside gives −0.1; one whose corner crossed the centre
    line by 0.2 m gives 0.2.
    """
    d = corner_offsets_m(log)
    return float(np.max(np.abs(d)) - 0.5 * log.meta.road.lane_width_m)


def graded_outcome(log: RunLog) -> GradedOutcome:
    """The :class:`GradedOutcome` of a run.

    Raises
    ------
    ValueError
        If the log has no time series.
    """
    ts = log.timeseries
    if ts.empty:
        raise ValueError("log has no timeseries rows: nothing to grade")
    collided = ts["in_collision"].astype(bool).to_numpy()
    collision = bool(collided.any())
    clearance = None
    if not collision and ts["passed_obstacle"].astype(bool).any():
        values = ts["clearance_m"].to_numpy(dtype=float)
        if np.isfinite(values).any():
            clearance = float(np.nanmin(values))
    return GradedOutcome(
        max_abs_offset_m=float(np.max(np.abs(ts["d_m"]))),
        lane_excursion_m=lane_excursion_m(log),
        left_lane=bool(ts["left_lane"].astype(bool).any()),
        entered_opposing_lane=bool(ts["in_opposing_lane"].astype(bool).any()),
        collision=collision,
        impact_speed_mps=(
            float(ts["speed_mps"].to_numpy()[np.argmax(collided)]) if collision else None
        ),
        min_clearance_m=clearance,
        peak_util_front=float(np.nanmax(ts["util_front"].to_numpy(dtype=float))),
    )
