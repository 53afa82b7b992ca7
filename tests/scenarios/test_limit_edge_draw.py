"""The edge-of-physics probe (`benchmarks/limit_edge_draw.py`): its campaign file loads, and every
variant it holds is feasible at the asked fraction of the oracle's highest entry speed."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from mufusion.campaign import campaign_specs, load_campaign
from mufusion.scenarios import load_scenario
from mufusion.scenarios.feasibility import FeasibilityClass, classify_scenario
from mufusion.vehicle.params import vehicle_preset

SCRIPT = Path(__file__).parents[2] / "benchmarks" / "limit_edge_draw.py"


def _script():
    spec = importlib.util.spec_from_file_location("limit_edge_draw", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("kind", ["turn", "popup"])
def test_every_drawn_variant_is_feasible_at_the_fraction_of_its_limit(kind, tmp_path):
    edge = _script()
    fraction = 0.9
    rows = edge.draw(kind, np.random.default_rng(3), 4, fraction)
    path = tmp_path / "edge.toml"
    path.write_text(edge.campaign_text(kind, rows, 3, fraction))
    specs = campaign_specs(load_campaign(path))
    assert [s.config for s in specs] == ["GT", "F-safe"] * 4
    assert sorted({s.overrides for s in specs}) == sorted(tuple(r) for r in rows)
    assert {r[0] for r in rows} == {"vehicle=truck", "vehicle=car"}  # the vehicles alternate
    for spec in specs[::2]:
        cfg = load_scenario(spec.scenario, list(spec.overrides))
        verdict = classify_scenario(cfg, vehicle_preset(cfg.vehicle))
        assert verdict.feasibility_class is FeasibilityClass.FEASIBLE
        highest = cfg.initial_speed_mps + verdict.margin_mps
        # The speed is rounded to 0.1 m/s.
        assert cfg.initial_speed_mps == pytest.approx(fraction * highest, abs=0.051)


def test_a_fraction_that_leaves_no_feasible_variant_is_refused(capsys):
    with pytest.raises(SystemExit) as stop:
        _script().main(["turn", "--fraction", "0.96"])
    assert stop.value.code == 2
    assert "--fraction must be in (0, 0.9524)" in capsys.readouterr().err


def test_the_configurations_are_the_users_and_a_misspelt_one_is_named_before_any_draw(capsys):
    edge = _script()
    text = edge.campaign_text("popup", [["vehicle=car", "friction.mu=0.5"]], 1, 0.9,
                              ["GT", "L", "P", "F"])
    assert 'configs = ["GT", "L", "P", "F"]' in text and "--configs GT L P F" in text
    with pytest.raises(SystemExit) as stop:
        edge.main(["turn", "--configs", "GT", "Fsafe"])
    assert stop.value.code == 2
    assert "'Fsafe' is neither a built-in configuration" in capsys.readouterr().err


def test_a_draw_lists_no_variant_twice():
    # Seed 14's pop-up draw repeated a quantised variant (the car at 16.3 m/s on μ 0.17, 29 m
    # ahead, centred), and `mufusion campaign` refused the file.
    rows = _script().draw("popup", np.random.default_rng(14), 80, 1 / 1.07)
    assert len(rows) == 80 and len({tuple(r) for r in rows}) == 80
