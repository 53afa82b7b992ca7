"""Explanations of differences are computed from the logs: they change with the data."""

from __future__ import annotations

from factories import estimate_grid, run_meta, tick
from mufusion.reproduction import explain_differences
from mufusion.sim.log import RunLog
from mufusion.sim.records import VehicleGeometry


def _saved_run(tmp_path, name: str, mu_hat: float, mu_true: float, width_m: float = 2.6):
    vehicle = VehicleGeometry(name="truck", length_m=6.28, width_m=width_m, wheelbase_m=3.4,
                              cog_to_front_axle_m=1.2, cog_to_rear_axle_m=2.2)
    log = RunLog(run_meta(vehicle=vehicle))
    for step, t in enumerate((0.0, 0.1)):
        log.append(estimate_grid(step, t, mu_hat, mu_true))
    log.append(tick())
    return str(log.save(tmp_path / name))


def _run(config: str, log: str, left_lane: bool, **extra) -> dict:
    return {"scenario": "turn", "variant": "turn-paper", "config": config, "log": log,
            "left_lane": left_lane, "entered_opposing_lane": left_lane,
            "max_abs_lateral_offset_m": 0.37, "max_force_excess": 0.24, **extra}


def test_turn_f_leaving_its_lane_is_explained_from_the_estimate_it_used(tmp_path):
    runs = [
        _run("F", _saved_run(tmp_path, "f", 0.447, 0.4), True),
        _run("F-safe", _saved_run(tmp_path, "fs", 0.4, 0.4), False),
        _run("GT", _saved_run(tmp_path, "gt", 0.4, 0.4), False),
    ]
    texts = explain_differences(runs)
    assert set(texts) == {"turn-paper/F/stays in lane"}
    text = texts["turn-paper/F/stays in lane"]
    assert "0.447" in text and "+11.7%" in text
    assert "F-safe" in text and "stayed in" in text
    assert "0.45 m of lane" in text


def test_a_different_log_gives_a_different_text_and_agreement_gives_none(tmp_path):
    other = [_run("F", _saved_run(tmp_path, "f2", 0.43, 0.4), True)]
    text = explain_differences(other)["turn-paper/F/stays in lane"]
    assert "0.430" in text and "+7.5%" in text and "F-safe" not in text
    agreeing = [_run("F", _saved_run(tmp_path, "f3", 0.4, 0.4), False)]
    assert explain_differences(agreeing) == {}
