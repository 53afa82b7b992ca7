"""A saved run log vouches for its tables: ``meta.json`` records each table's row count and
checksum, and a table that was truncated, altered or removed is refused on load, naming the file.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from factories import planning_step, run_meta, ticks
from mufusion.sim.log import STAMPS_KEY, RunLog, load_run
from mufusion.sim.records import Event

GOLDEN = Path(__file__).resolve().parents[1] / "data" / "golden_popup_F"


@pytest.fixture
def saved(tmp_path: Path) -> Path:
    log = RunLog(run_meta())
    log.extend(ticks(50, speed_mps=[10.0 + 0.1 * i for i in range(50)]))
    log.extend(planning_step(step=i, t_s=0.1 * i) for i in range(5))
    log.append(Event(t_s=0.4, kind="camera_dropout", detail="injected"))
    return log.save(tmp_path / "run")


def test_a_saved_log_loads_and_its_meta_records_every_table(saved: Path) -> None:
    meta = json.loads((saved / "meta.json").read_text())
    assert meta[STAMPS_KEY]["timeseries.csv"]["rows"] == 50
    assert meta[STAMPS_KEY]["planning_steps.csv"]["rows"] == 5
    assert meta[STAMPS_KEY]["events.csv"]["rows"] == 1
    back = load_run(saved)
    assert len(back.timeseries) == 50 and back.events["kind"].tolist() == ["camera_dropout"]


def test_a_truncated_table_is_refused_naming_the_file(saved: Path) -> None:
    file = saved / "timeseries.csv"
    lines = file.read_text().splitlines(keepends=True)
    file.write_text("".join(lines[:30]))  # a crash cut the file after 29 rows
    with pytest.raises(ValueError, match=r"timeseries\.csv.*29 rows.*records 50.*truncated"):
        load_run(saved)


def test_a_table_cut_inside_its_last_row_is_refused(saved: Path) -> None:
    file = saved / "timeseries.csv"
    data = file.read_bytes()
    file.write_bytes(data[: data.rindex(b",", 0, len(data) - 2)])  # same rows, cells missing
    with pytest.raises(ValueError, match=r"timeseries\.csv"):
        load_run(saved)


def test_an_altered_value_is_refused_naming_the_file(saved: Path) -> None:
    file = saved / "planning_steps.csv"
    text = file.read_text()
    header, first, rest = text.split("\n", 2)
    file.write_text("\n".join([header, first.replace("cruise", "emergency", 1), rest]))
    with pytest.raises(ValueError, match=r"planning_steps\.csv.*checksum.*altered"):
        load_run(saved)


def test_a_removed_table_is_refused_naming_the_file(saved: Path) -> None:
    (saved / "events.csv").unlink()
    with pytest.raises(ValueError, match=r"events\.csv.*missing"):
        load_run(saved)


def test_a_log_saved_before_the_stamps_still_loads(saved: Path) -> None:
    meta_file = saved / "meta.json"
    meta = json.loads(meta_file.read_text())
    del meta[STAMPS_KEY]
    meta_file.write_text(json.dumps(meta))
    assert len(load_run(saved).timeseries) == 50


def test_the_golden_logs_tables_still_load_as_a_run(saved: Path, tmp_path: Path) -> None:
    # The golden recording keeps its tables only (tests/sim/test_golden_log.py reads them as
    # they are); beside a meta.json without stamps, as every run saved before them has, they
    # load as a run.
    run = tmp_path / "golden"
    run.mkdir()
    for table in GOLDEN.glob("*.csv"):
        (run / table.name).write_bytes(table.read_bytes())
    meta = json.loads((saved / "meta.json").read_text())
    del meta[STAMPS_KEY]
    (run / "meta.json").write_text(json.dumps(meta))
    log = load_run(run)
    assert len(log.timeseries) == len((GOLDEN / "timeseries.csv").read_text().splitlines()) - 1
