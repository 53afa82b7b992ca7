"""Our time to collision and time to brake against commonroad-crime's (optional).

commonroad-crime (CommonRoad's criticality measures) is not a dependency of mufusion: its tree
(the drivability checker, commonroad-reach, CasADi) is heavy. Where it is installed this test
builds the same straight road, the same ego trajectory and one other vehicle in CommonRoad and
in a mufusion log, and compares the measures at the first tick.

* TTC: commonroad-crime's ``TTC`` (constant velocities, the headway along the lanelet from the
  ego's front to the other's rear) is ours up to its rounding to 0.01 s.
* TTB: commonroad-crime's ``TTB`` simulates the ego braking from each time step on and searches
  the last step from which it avoids the other's trajectory, at the resolution of the
  scenario's time step. Its braking is set to ours (``λ μ g``, no jerk limit); it then agrees
  with ours to within one and a half steps (a point mass integrated step by step).
"""

from __future__ import annotations

import numpy as np
import pytest

from factories import run_meta, ticks
from mufusion.metrics.criticality import criticality
from mufusion.sim.log import RunLog
from mufusion.sim.records import ObstacleTrace

crime = pytest.importorskip("commonroad_crime")

from commonroad.geometry.shape import Rectangle  # noqa: E402
from commonroad.prediction.prediction import TrajectoryPrediction  # noqa: E402
from commonroad.scenario.lanelet import Lanelet  # noqa: E402
from commonroad.scenario.obstacle import DynamicObstacle, ObstacleType  # noqa: E402
from commonroad.scenario.scenario import Scenario  # noqa: E402
from commonroad.scenario.state import CustomState, InitialState  # noqa: E402
from commonroad.scenario.trajectory import Trajectory  # noqa: E402
from commonroad_crime.data_structure.configuration import CriMeConfiguration  # noqa: E402
from commonroad_crime.measure.time.ttb import TTB  # noqa: E402
from commonroad_crime.measure.time.ttc import TTC  # noqa: E402

DT_S = 0.1
STEPS = 120
EGO_SPEED = 20.0
EGO_S0 = 20.0  # the CoG's progress at time 0
MU = 0.5
# The factories' truck: 6.28 m × 2.6 m, its footprint's centre 0.5 m behind the CoG.
EGO_LENGTH, EGO_WIDTH, EGO_CENTRE_AHEAD = 6.28, 2.6, -0.5
OTHER_LENGTH, OTHER_WIDTH = 4.5, 1.8


def _vehicle(oid: int, x0: float, speed: float, length: float, width: float) -> DynamicObstacle:
    states = [CustomState(time_step=k, position=np.array([x0 + speed * k * DT_S, 0.0]),
                          orientation=0.0, velocity=speed, velocity_y=0.0, acceleration=0.0,
                          acceleration_y=0.0) for k in range(STEPS)]
    initial = InitialState(time_step=0, position=states[0].position, orientation=0.0,
                           velocity=speed, acceleration=0.0, yaw_rate=0.0, slip_angle=0.0)
    initial.velocity_y = 0.0
    initial.acceleration_y = 0.0
    shape = Rectangle(length, width)
    return DynamicObstacle(oid, ObstacleType.CAR, shape, initial,
                           TrajectoryPrediction(Trajectory(1, states[1:]), shape))


def _crime(other_s0: float, other_speed: float, decel: float) -> tuple[float, float]:
    scenario = Scenario(dt=DT_S)
    scenario.add_objects(Lanelet(
        np.array([[0.0, 1.75], [600.0, 1.75]]), np.array([[0.0, 0.0], [600.0, 0.0]]),
        np.array([[0.0, -1.75], [600.0, -1.75]]), lanelet_id=1))
    scenario.add_objects([
        _vehicle(10, EGO_S0 + EGO_CENTRE_AHEAD, EGO_SPEED, EGO_LENGTH, EGO_WIDTH),
        _vehicle(11, other_s0, other_speed, OTHER_LENGTH, OTHER_WIDTH),
    ])
    scenario.assign_obstacles_to_lanelets()
    config = CriMeConfiguration()
    config.update(ego_id=10, sce=scenario)
    ttc = TTC(config).compute(11, 0, verbose=False)
    # Brake as ours does: λ μ g at once.
    config.vehicle.params.longitudinal.a_max = decel
    config.vehicle.cartesian.a_x_min = -decel
    config.vehicle.cartesian.j_x_min, config.vehicle.cartesian.j_x_max = -1e6, 1e6
    ttb = TTB(config).compute(0, 11, verbose=False)
    return float(ttc), float(ttb)


@pytest.mark.parametrize(("other_s0", "other_speed"), [(80.0, 10.0), (90.0, 0.0)])
def test_ttc_and_ttb_agree_with_commonroad_crime(other_s0: float, other_speed: float) -> None:
    t = np.arange(5) * 0.02
    obstacle = ObstacleTrace(s_m=other_s0, d_m=0.0, length_m=OTHER_LENGTH, width_m=OTHER_WIDTH,
                             appear_time_s=None, corners_x_m=[0.0] * 4, corners_y_m=[0.0] * 4,
                             speed_mps=other_speed)
    log = RunLog(run_meta(obstacles=[obstacle]))
    log.extend(ticks(t.size, s_m=EGO_S0 + EGO_SPEED * t, vx_mps=EGO_SPEED, speed_mps=EGO_SPEED,
                     mu_front=MU, mu_rear=MU))
    ours = criticality(log)
    assert ours is not None
    decel = log.meta.planner.utilization_factor * MU * 9.81
    ttc, ttb = _crime(other_s0, other_speed, decel)
    assert ours.time_to_collision_s[0] == pytest.approx(ttc, abs=0.006)
    assert ours.time_to_brake_s[0] == pytest.approx(ttb, abs=1.5 * DT_S)
