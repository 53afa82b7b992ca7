"""Perturbed starts: seeded draws around the initial state, validated, recorded, driven."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.metrics.run_metrics import compute_metrics
from mufusion.scenarios import load_scenario
from mufusion.scenarios.config import InitialPerturbation, perturbed
from mufusion.scenarios.runner import run_scenario


@pytest.mark.parametrize(
    ("overrides", "fragment"),
    [
        (["perturbation.speed_mps=2.5"], "perturbation.speed_mps"),
        (["perturbation.lateral_offset_m=-0.1"], "perturbation.lateral_offset_m"),
        (["perturbation.heading_rad=0.2"], "perturbation.heading_rad"),
        (["initial_speed_mps=1.5", "perturbation.speed_mps=1.5"], "perturbation.speed_mps must"),
        (["initial_lateral_offset_m=0.8", "perturbation.lateral_offset_m=0.3"],
         "perturbation.lateral_offset_m plus"),
        (["initial_heading_error_rad=-0.15", "perturbation.heading_rad=0.06"],
         "perturbation.heading_rad plus"),
        (["initial_lateral_offset_m=1.2"], "initial_lateral_offset_m"),
    ],
)
def test_bad_starts_name_the_field(overrides: list[str], fragment: str) -> None:
    with pytest.raises(ValueError, match=fragment.replace(".", r"\.")):
        load_scenario("turn", overrides)


def test_without_a_perturbation_nothing_is_drawn() -> None:
    cfg = load_scenario("popup")
    rng = np.random.default_rng(5)
    before = rng.bit_generator.state
    assert perturbed(cfg, rng) is cfg
    assert rng.bit_generator.state == before


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**31),
    speed=st.floats(0.0, 2.0),
    offset=st.floats(0.0, 0.5),
    heading=st.floats(0.0, 0.1),
)
def test_draws_stay_within_their_half_widths(
    seed: int, speed: float, offset: float, heading: float
) -> None:
    cfg = load_scenario("turn", [
        "initial_speed_mps=14", "initial_lateral_offset_m=0.2", "initial_heading_error_rad=-0.05",
        f"perturbation.speed_mps={speed!r}", f"perturbation.lateral_offset_m={offset!r}",
        f"perturbation.heading_rad={heading!r}",
    ])
    drawn = perturbed(cfg, np.random.default_rng(seed))
    again = perturbed(cfg, np.random.default_rng(seed))
    assert drawn == again  # the seed decides
    assert abs(drawn.initial_speed_mps - 14.0) <= speed
    assert abs(drawn.initial_lateral_offset_m - 0.2) <= offset
    assert abs(drawn.initial_heading_error_rad + 0.05) <= heading
    # The set speed stays the scenario's; the result is concrete (nothing left to draw).
    assert drawn.cruise_speed_mps == 14.0
    assert drawn.perturbation == InitialPerturbation()


def test_a_zero_half_width_leaves_the_other_draws_alone() -> None:
    base = ["perturbation.lateral_offset_m=0.3", "perturbation.heading_rad=0.05"]
    with_speed = perturbed(load_scenario("turn", [*base, "perturbation.speed_mps=1"]),
                           np.random.default_rng(3))
    without = perturbed(load_scenario("turn", base), np.random.default_rng(3))
    assert without.initial_speed_mps == 12.0 != with_speed.initial_speed_mps
    assert with_speed.initial_lateral_offset_m == without.initial_lateral_offset_m != 0.0
    assert with_speed.initial_heading_error_rad == without.initial_heading_error_rad != 0.0


def _start(overrides: list[str]) -> tuple[float, float, float, dict]:
    log = run_scenario(load_scenario("turn", ["duration_s=0.3", *overrides]), "GT")
    m = compute_metrics(log)
    assert m.start_speed_mps is not None
    assert m.start_lateral_offset_m is not None and m.start_heading_error_rad is not None
    return (m.start_speed_mps, m.start_lateral_offset_m, m.start_heading_error_rad,
            log.meta.scenario_config)


def test_runs_start_where_drawn_and_record_it() -> None:
    fixed = _start(["initial_lateral_offset_m=0.3", "initial_heading_error_rad=0.04"])
    assert fixed[:3] == pytest.approx((12.0, 0.3, 0.04), abs=1e-9)
    pert = ["perturbation.speed_mps=0.5", "perturbation.lateral_offset_m=0.2",
            "perturbation.heading_rad=0.05"]
    a, b, c = (_start([*pert, f"seed={seed}"]) for seed in (1, 1, 2))
    assert a[:3] == b[:3]  # same seed, same start
    assert a[:3] != c[:3]
    for speed, offset, heading, meta in (a, c):
        # The metadata holds the concrete start that was driven, and the run started there.
        assert (speed, offset, heading) == pytest.approx(
            (meta["initial_speed_mps"], meta["initial_lateral_offset_m"],
             meta["initial_heading_error_rad"]), abs=1e-9)
        assert meta["reference_speed_mps"] == 12.0
        assert (abs(speed - 12.0) <= 0.5 and abs(offset) <= 0.2 and abs(heading) <= 0.05)
