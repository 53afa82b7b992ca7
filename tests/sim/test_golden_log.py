"""Refactorings keep behaviour: a short pop-up run reproduces its recorded log exactly.

``tests/data/golden_popup_F`` holds the full log (time series, planning steps, plans, estimates)
of ``popup`` with configuration F for 1.5 s, recorded before the run log got its typed records.
Every recorded column must come out the same (to 1e-9); new columns may be added. When a change
is *meant* to alter the closed loop, regenerate the files with

    python tests/sim/test_golden_log.py

and say so in the commit.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import run_scenario

GOLDEN = Path(__file__).resolve().parents[1] / "data" / "golden_popup_F"
TABLES = ("timeseries", "planning_steps", "plans", "estimates")


def _run():
    return run_scenario(load_scenario("popup", ["duration_s=1.5"]), "F")


@pytest.fixture(scope="module")
def log():
    return _run()


@pytest.mark.parametrize("table", TABLES)
def test_log_matches_the_recorded_run(log, table: str) -> None:
    expected = pd.read_csv(GOLDEN / f"{table}.csv")
    actual = pd.read_csv(pd.io.common.StringIO(log.frame(table).to_csv(index=False,
                                                                          float_format="%.9g")))
    assert len(actual) == len(expected)
    for column in expected.columns:
        assert column in actual.columns, f"{table}.{column} disappeared"
        want, got = expected[column], actual[column]
        if want.dtype.kind in "fiu":
            np.testing.assert_allclose(
                got.to_numpy(float), want.to_numpy(float), rtol=1e-9, atol=1e-9,
                err_msg=f"{table}.{column}",
            )
        else:
            assert (got.astype(str) == want.astype(str)).all(), f"{table}.{column}"


if __name__ == "__main__":  # regenerate
    run = _run()
    GOLDEN.mkdir(parents=True, exist_ok=True)
    for name in TABLES:
        run.frame(name).to_csv(GOLDEN / f"{name}.csv", index=False, float_format="%.9g")
    sys.exit(0)
