"""Bad input on the command line: exit code 2 and the field named, before any simulation."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from mufusion.cli import app
from processes import child_environment


def _run(*args: str):
    return CliRunner().invoke(app, list(args))


def _said(result) -> str:
    return " ".join(result.output.split())


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["run", "turn", "--set", "friction.mu=0.1"], "unknown key 'friction.mu' for the 'turn'"),
        (["run", "turn", "--set", "obstacle.distance_m=20"], "unknown key 'obstacle'"),
        (["run", "popup", "--set", "turn.radius_m=30"], "unknown key 'turn'"),
        (["run", "turn", "--set", "initial_speed_mps=true"], "initial_speed_mps: expected a"),
        (["run", "turn", "--set", "seed=1", "--set", "seed=2"], "'seed' is given more than once"),
        (["run", "popup", "--set", "duration_s=0.4"], "duration_s must exceed"),
        (["run", "popup", "--set", "sim.controller_rate_hz=60"], "sim.controller_rate_hz"),
        (["run", "turn", "--set", "perturbation.speed_mps=13"], "perturbation.speed_mps"),
        (["run", "turn", "--set", "planner.reference_braking_fraction=0"],
         "planner.reference_braking_fraction"),
        (["run", "turn", "--set", "planner.reference_regain_limit=2"],
         "planner.reference_regain_limit"),
        (["run", "popup", "-c", "F_safe"], "'F_safe' is neither a built-in configuration"),
        (["run", "popup", "-c", "GT", "-c", "F"], "--config: run drives one configuration, got 2"),
        (["run", "nowhere.toml"], "does not exist"),
    ],
)
def test_bad_run_input_exits_2_naming_the_field(args, fragment: str, tmp_path: Path) -> None:
    result = _run(*args, "--out", str(tmp_path / "out"))
    assert result.exit_code == 2, result.output
    assert fragment in _said(result)
    assert not (tmp_path / "out").exists()  # nothing was run or written


def test_out_pointing_at_a_file_is_refused_before_the_run(tmp_path: Path) -> None:
    target = tmp_path / "taken"
    target.write_text("not a directory")
    for command in (["run", "popup"], ["reproduce"]):
        result = _run(*command, "--out", str(target))
        assert result.exit_code == 2, result.output
        assert "is a file, not a directory" in _said(result)
    nested = _run("run", "popup", "--out", str(target / "sub"))
    assert nested.exit_code == 2 and "is a file" in _said(nested)


def test_a_binary_scenario_file_is_named(tmp_path: Path) -> None:
    path = tmp_path / "garbage.toml"
    path.write_bytes(bytes(range(256)))
    result = _run("run", str(path), "--out", str(tmp_path / "out"))
    assert result.exit_code == 2
    # The message may break the long temporary path anywhere (a parallel worker's is longer).
    assert "garbage.toml" in "".join(result.output.split())


# What a command refused for bad input must not have imported: the solver stack, the plotting,
# the tables and SciPy (each costs a large part of a second; together they took 3 s).
HEAVY = ("acados_template", "casadi", "matplotlib", "pandas", "scipy", "mufusion.sim.loop")

_IMPORTED_AT_EXIT = """
import atexit, json, runpy, sys
out = sys.argv.pop(1)
def record():
    with open(out, "w") as f:
        json.dump(sorted(sys.modules), f)
atexit.register(record)
sys.argv[0] = "mufusion"
runpy.run_module("mufusion", run_name="__main__", alter_sys=True)
"""


def _modules_after(tmp_path: Path, *args: str) -> tuple[subprocess.CompletedProcess, set[str]]:
    """Run ``python -m mufusion ARGS`` in a fresh interpreter; its result and what it imported."""
    record = tmp_path / "modules.json"
    result = subprocess.run(
        [sys.executable, "-c", _IMPORTED_AT_EXIT, str(record), *args],
        capture_output=True, text=True, env=child_environment(), timeout=120,
    )
    return result, set(json.loads(record.read_text()))


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["run", "turn", "--set", "friction.mu_turn=7"], "friction.mu_turn"),
        (["run", "popup", "-c", "F_safe"], "'F_safe' is neither a built-in configuration"),
        (["reproduce", "--jobs", "0"], "--jobs must be >= 1"),
    ],
)
def test_bad_input_is_refused_before_the_heavy_stack_loads(tmp_path, args, fragment) -> None:
    result, modules = _modules_after(tmp_path, *args, "--out", str(tmp_path / "out"))
    assert result.returncode == 2, result.stderr
    assert fragment in " ".join(result.stderr.split())
    loaded = [m for m in HEAVY if m in modules]
    assert not loaded, f"imported before refusing the input: {loaded}"
    assert "mufusion.scenarios" in modules or args[0] == "reproduce"  # the check did run


def test_a_bad_campaign_file_is_refused_before_the_heavy_stack_loads(tmp_path) -> None:
    file = tmp_path / "c.toml"
    file.write_text('name = "t"\nscenarios = ["popup"]\nconfigs = ["GT"]\n'
                    '[grid]\n"friction.mu" = [0.8, 9.0]\n')
    result, modules = _modules_after(tmp_path, "campaign", str(file), "--out",
                                     str(tmp_path / "out"))
    assert result.returncode == 2, result.stderr
    assert "friction.mu" in " ".join(result.stderr.split())
    loaded = [m for m in HEAVY if m in modules]
    assert not loaded, f"imported before refusing the input: {loaded}"
