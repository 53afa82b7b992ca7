"""np.minimum(np.maximum(x, lo), hi) gives np.clip's values for the non-zero bounds it replaces."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from mufusion.configurations.interface import MU_HAT_MAX, MU_HAT_MIN
from mufusion.planner.ocp import MAX_SWING_HEADING_RAD, MU_MAX, MU_MIN

BOUNDS = [(MU_MIN, MU_MAX), (-MAX_SWING_HEADING_RAD, MAX_SWING_HEADING_RAD), (0.05, 2.0),
          (MU_HAT_MIN, MU_HAT_MAX)]


@pytest.mark.parametrize(("lo", "hi"), BOUNDS)
@settings(max_examples=100, deadline=None)
@given(x=arrays(np.float64, st.integers(0, 60), elements=st.floats(allow_nan=True,
                                                                      allow_infinity=True)))
def test_min_max_is_clip(lo: float, hi: float, x: np.ndarray) -> None:
    assert lo != 0.0 and hi != 0.0  # signed zeros are where the two could differ
    extra = np.array([lo, hi, -0.0, 0.0, np.nextafter(lo, -1.0), np.nextafter(hi, 3.0)])
    values = np.concatenate([x, extra])
    got, expected = np.minimum(np.maximum(values, lo), hi), np.clip(values, lo, hi)
    assert got.tobytes() == expected.tobytes()
