"""The loop's friction estimation: the sensors observe each plant step, the source estimates at
each planning step (what the loop injects as faults degrades its inputs).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from mufusion.configurations import FrictionEstimate, FrictionSource, channels_of, step_source
from mufusion.estimators import Channel, SensorModel, VehicleSignals
from mufusion.sim.sensing import vehicle_signals
from mufusion.sim.world import World
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.plant import PlantOutput


def source_grid_m(
    estimate_grid_m: np.ndarray, friction: FrictionSource, truth_reach_m: float
) -> np.ndarray:
    """The distances ahead at which ``friction`` is handed its inputs and gives μ̂ [m].

    The sensors' grid ``estimate_grid_m`` (the paper's 0, 1, …, 50 m: the camera's range), or,
    for a source that reads the truth (:attr:`~mufusion.estimators.Channel.TRUTH`, GT), that
    grid continued at its own spacing to ``truth_reach_m``: the paper's GT plans with
    ``μ̂(s) = μ_gt(s)`` over the whole horizon, not up to a camera's range. Held at 50 m, GT
    was blind to a drop the planner's reach already covered: a truck at 23 m/s that needs 49 m
    to brake for a drop 55 m ahead spun 13 m off its lane (docs/decisions/0071).

    Raises
    ------
    ValueError
        If ``truth_reach_m`` is not finite or ends before the sensors' grid does.

    Examples
    --------
    >>> from mufusion.configurations import make_estimator
    >>> grid = np.arange(0.0, 51.0)
    >>> source_grid_m(grid, make_estimator("GT"), 300.0)[[0, 50, 51, -1]].tolist()
    [0.0, 50.0, 51.0, 300.0]
    >>> source_grid_m(grid, make_estimator("L"), 300.0) is grid
    True
    """
    grid = np.asarray(estimate_grid_m, dtype=float)
    if not (np.isfinite(truth_reach_m) and truth_reach_m >= grid[-1]):
        raise ValueError(f"truth_reach_m must be finite and at least the estimate grid's end "
                         f"({grid[-1]:g} m), got {truth_reach_m!r}")
    if Channel.TRUTH not in channels_of(friction):
        return estimate_grid_m
    step = float(grid[-1] - grid[-2]) if grid.size > 1 else 1.0
    beyond = np.arange(grid[-1] + step, truth_reach_m + 0.5 * step, step)
    return np.concatenate([grid, beyond])


class FrictionEstimation:
    """A friction source on a vehicle's sensors, stepped by the loop.

    Parameters
    ----------
    friction
        The friction source (:class:`~mufusion.configurations.FrictionSource`).
    sensors
        The vehicle's emulated sensors: the only part that reads the true friction.
    world
        Road and true friction.
    params
        Vehicle parameters (axle positions, for the signals).
    estimate_grid_m
        Distances ahead at which friction is estimated [m].
    """

    def __init__(
        self,
        friction: FrictionSource,
        sensors: SensorModel,
        world: World,
        params: VehicleParams,
        estimate_grid_m: np.ndarray,
    ) -> None:
        self.friction = friction
        self.sensors = sensors
        self.world = world
        self.params = params
        self.grid_m = estimate_grid_m
        # The source's interface: its channels, and its per-plant-step call if it has one.
        self._channels = channels_of(friction)
        self._observe: Callable[[VehicleSignals], None] | None = getattr(
            friction, "observe", None)
        self._last_output: tuple[float, PlantOutput] | None = None  # (its time, the output)

    def initial(self, x_plant: np.ndarray, s_ego_m: float) -> FrictionEstimate:
        """The estimate at the start, the tires having rolled freely (for the warm-up plans)."""
        # The local estimator has seen the tires rolling freely at the start.
        self.sensors.observe(0.0, 0.0, 0.0, *self.world.friction_under_axles(x_plant, self.params))
        return step_source(
            self.friction, self.sensors, self.grid_m,
            self.world.friction(s_ego_m + self.grid_m), 0.0, t_s=0.0, channels=self._channels,
            s_ego_m=s_ego_m,
        )

    def estimate(
        self, t_s: float, s_ego_m: float, utilization: float, kinds: frozenset[str]
    ) -> FrictionEstimate:
        """One planning step's estimate under the active fault ``kinds`` (it may raise: the
        source's exception)."""
        mu_true = self.world.friction(s_ego_m + self.grid_m)
        util = 0.0 if "local_dropout" in kinds else utilization
        # An absent camera, or one whose values are NaN, gives nothing usable: discarded.
        camera_ok = not ({"camera_dropout", "camera_nan"} & kinds)
        return step_source(
            self.friction, self.sensors, self.grid_m, mu_true, util,
            camera_ok=camera_ok, t_s=t_s, channels=self._channels,
            signals=None if self._last_output is None else vehicle_signals(
                *self._last_output, self.params),
            s_ego_m=s_ego_m,
        )

    def observe(self, t_s: float, output: PlantOutput, mu_front: float, mu_rear: float) -> None:
        """What the sensors (and a source that observes) see of one plant step ending at ``t_s``."""
        self.sensors.observe(t_s, output.utilization_front, output.utilization_rear,
                             mu_front, mu_rear)
        self._last_output = (t_s, output)
        if self._observe is not None:
            self._observe(vehicle_signals(t_s, output, self.params))
