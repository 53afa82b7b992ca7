"""The plant's two state views (array indices and named floats) describe the same layout."""

from __future__ import annotations

import numpy as np

from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import TRUCK
from mufusion.vehicle.plant import Plant
from mufusion.vehicle.plant_state import (
    N_PLANT_STATES,
    PlantState,
    PlantStateVector,
    initial_state,
    state_vector,
)


def test_index_enum_and_named_tuple_declare_the_same_order() -> None:
    assert len(PlantStateVector._fields) == N_PLANT_STATES
    for member, field in zip(PlantState, PlantStateVector._fields, strict=True):
        # Field = enum name in lower case plus a unit suffix (x_m for X, steer_rad for STEER).
        assert field.startswith(member.name.lower() + "_"), (member, field)
        assert PlantStateVector._fields.index(field) == int(member)


def test_named_view_reads_the_same_numbers_as_the_array_view() -> None:
    x = initial_state(TRUCK, 1.0, 2.0, 0.3, 12.0)
    x[PlantState.STEER] = 0.05
    x[PlantState.TORQUE_REAR] = -300.0
    named = state_vector(x)
    assert named.x_m == 1.0 and named.y_m == 2.0 and named.psi_rad == 0.3
    assert named.vx_mps == 12.0 and named.steer_rad == 0.05 and named.torque_rear_nm == -300.0
    plant = Plant(TRUCK, x)
    plant.step(ActuatorCommand(0.02, 0.0, -500.0), 0.8, 0.8)
    assert np.array_equal(plant.x, np.asarray(plant.state))
    assert plant.state.steer_rad == plant.x[PlantState.STEER]
