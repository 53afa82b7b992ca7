"""Event kinds are an enum whose members enter the log as the plain strings logs always held."""

from __future__ import annotations

from pathlib import Path

from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import run_scenario
from mufusion.sim.events import EventKind
from mufusion.sim.log import load_run


def test_event_kinds_enter_the_log_as_plain_strings_and_load_back(tmp_path: Path) -> None:
    fault = '{kind="solver_failure", start_s=0.0, duration_s=1.0}'
    log = run_scenario(load_scenario("popup", ["duration_s=0.6", f"faults=[{fault}]"]), "F")
    kinds = log.events["kind"].tolist()
    # The fault is scheduled, and the planner's failures in a row start the manoeuvre.
    assert kinds[0] == EventKind.FAULT_SCHEDULED and EventKind.MINIMAL_RISK in kinds
    assert all(type(kind) is str for kind in kinds)  # not the enum: the CSV and hashes unchanged
    assert load_run(log.save(tmp_path / "run")).events["kind"].tolist() == kinds


def test_every_kind_is_its_own_value() -> None:
    values = [kind.value for kind in EventKind]
    assert len(set(values)) == len(values)
    assert all(EventKind(value).value == value == f"{EventKind(value)}" for value in values)
