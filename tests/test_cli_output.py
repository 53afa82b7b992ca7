"""What a newcomer sees: progress and results only. The solver library's messages go into the
run log and the summary's count, never onto the terminal; the outcome table fits 80 columns."""

from __future__ import annotations

import io
import json
import subprocess
from pathlib import Path

from rich.console import Console

from mufusion.cli_table import print_outcome_table
from mufusion.reproduction import reproduction_specs
from processes import child_environment, mufusion_command

# F-safe, the truck at 21 m/s with an obstacle 15 m ahead on μ 0.8 (infeasible: it hits at about
# 18 m/s): at the end its QPs stop early, which acados reports with printf ("SQP_RTI: QP solver
# returned error status 3 ..."). The turn this test used before solves every QP since HPIPM's
# SPEED_ABS mode (decision 0102).
NOISY_RUN = ["popup", "-c", "F-safe", "--set", "vehicle=truck", "--set", "friction.mu=0.8",
             "--set", "initial_speed_mps=21", "--set", "obstacle.distance_m=15",
             "--set", "obstacle.lateral_offset_m=0.0"]


def test_solver_messages_are_counted_and_logged_never_printed(tmp_path: Path) -> None:
    out = tmp_path / "run"
    result = subprocess.run(
        mufusion_command("run", *NOISY_RUN, "--no-gif", "--out", str(out)),
        capture_output=True, text=True, env={**child_environment(), "COLUMNS": "80"},
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    for stream in (result.stdout, result.stderr):
        assert "SQP_RTI" not in stream and "QP solver" not in stream, stream
        assert "CasADi" not in stream, stream
    assert max(len(line) for line in result.stdout.splitlines()) <= 80, result.stdout
    summary = json.loads((out / "summary.json").read_text())
    logged = (out / "log" / "solver_messages.txt").read_text().splitlines()
    assert summary["solver_messages"] == len(logged) > 0
    assert all(line.startswith("SQP_RTI: QP solver returned error status") for line in logged)


def _reproduce_like_rows() -> list[dict]:
    specs = reproduction_specs(include_car=True)
    return [{"scenario": s.scenario, "variant": s.variant, "config": s.config,
             "collision": i % 4 == 0, "impact_speed_mps": 12.345 if i % 4 == 0 else None,
             "min_clearance_m": None if i % 4 == 0 else 0.7114,
             "max_lane_excursion_m": 3.7361, "time_outside_lane_s": 2.96,
             "max_opposing_lane_depth_m": 1.234, "utilization_vs_gt": -0.1234 * (i % 3)}
            for i, s in enumerate(specs)]


def _rendered(rows: list[dict], width: int) -> list[str]:
    console = Console(file=io.StringIO(), width=width, force_terminal=False)
    print_outcome_table(rows, console)
    return console.file.getvalue().splitlines()  # type: ignore[attr-defined]


def test_the_outcome_table_fits_80_columns_one_line_per_run() -> None:
    rows = _reproduce_like_rows()
    wide = _rendered(rows, 200)
    assert max(len(line) for line in wide) > 80  # the full layout would not fit
    lines = _rendered(rows, 80)
    assert max(len(line) for line in lines) <= 80, "\n".join(lines)
    for row in rows:  # each run on one line, its cells unbroken
        assert sum(line.split()[:2] == [row["variant"], row["config"]] for line in lines) == 1


def test_a_wide_terminal_keeps_the_full_layout_and_columns_80_is_honoured(monkeypatch) -> None:
    rows = _reproduce_like_rows()
    assert any("┃" in line for line in _rendered(rows, 200))  # boxed, headers on one line
    monkeypatch.setenv("COLUMNS", "80")
    console = Console(file=io.StringIO(), force_terminal=False)
    print_outcome_table(rows, console)
    assert max(map(len, console.file.getvalue().splitlines())) <= 80  # type: ignore[attr-defined]
