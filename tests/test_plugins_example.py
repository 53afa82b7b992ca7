"""The plug-in example (examples/plugins) runs through the CLI like a built-in configuration.

The CLI imports a plug-in from the current directory, as ``python -m`` does; the commands that
name a plug-in run here from the repository root with only the package's own ``src`` on
PYTHONPATH, so the example is found the way a user's module next to their campaign file is.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
import tomllib
from typer.testing import CliRunner

import mufusion
from mufusion.cli import app

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "plugins"
SPEC = "examples.plugins.recursive_slip:RecursiveSlip"


def _mufusion(*args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(Path(mufusion.__file__).parents[1])}
    return subprocess.run([sys.executable, "-m", "mufusion", *args], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=900)


def test_the_campaign_file_compares_the_plugin_with_the_paper_configurations() -> None:
    plan = tomllib.loads((EXAMPLE / "compare.toml").read_text())
    assert plan["configs"][:4] == ["GT", "L", "P", "F"] and plan["configs"][4] == SPEC


def test_mufusion_run_takes_the_plugin_by_import_path(tmp_path: Path) -> None:
    out = tmp_path / "run"
    done = _mufusion("run", "popup", "--config", SPEC, "--set", "duration_s=0.6", "--out",
                     str(out), "--no-gif")
    assert done.returncode == 0, done.stderr
    assert json.loads((out / "summary.json").read_text())["config"] == SPEC
    assert json.loads((out / "log" / "meta.json").read_text())["configuration"] == SPEC


def test_a_broken_plugin_fails_before_any_run_naming_it(tmp_path: Path) -> None:
    done = _mufusion("run", "popup", "--config", "examples.plugins.recursive_slip:Nope",
                     "--out", str(tmp_path / "run"))
    assert done.returncode == 2
    assert "examples.plugins.recursive_slip:Nope" in " ".join(done.stderr.split())
    assert not (tmp_path / "run").exists()


def test_a_planner_plugin_without_its_calls_fails_before_any_run(tmp_path: Path) -> None:
    done = _mufusion("run", "popup", "--planner", "json:JSONDecoder", "--out",
                     str(tmp_path / "run"))
    assert done.returncode == 2
    said = " ".join(done.stderr.split())
    assert "--planner: plug-in 'json:JSONDecoder' is not a planner" in said
    assert not (tmp_path / "run").exists()


def test_a_campaign_naming_a_broken_plugin_fails_before_any_run(tmp_path: Path) -> None:
    file = tmp_path / "broken.toml"
    file.write_text('scenarios = ["popup"]\nconfigs = ["GT", "examples.plugins.nowhere:X"]\n')
    done = _mufusion("campaign", str(file), "--out", str(tmp_path / "out"))
    assert done.returncode == 2
    assert "plug-in 'examples.plugins.nowhere:X'" in " ".join(done.stderr.split())
    assert not (tmp_path / "out" / "runs").exists()


@pytest.fixture(scope="module")
def campaign(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A tiny version of compare.toml: one friction level (an override, not a grid of one
    point, whose 30 one-cell heat maps took most of this test's time), 0.6 s runs."""
    tmp = tmp_path_factory.mktemp("plugins")
    text = (EXAMPLE / "compare.toml").read_text()
    text = text.replace('overrides = ["duration_s=3.0"]',
                        'overrides = ["duration_s=0.6", "friction.mu=0.6"]')
    text = text.replace('[grid]\n"friction.mu" = [0.6, 0.8, 1.0]\n', "")
    assert "[grid]" not in text and '"duration_s=0.6", "friction.mu=0.6"' in text
    file = tmp / "tiny.toml"
    file.write_text(text)
    out = tmp / "campaign"
    done = _mufusion("campaign", str(file), "--out", str(out), "--jobs", "1")
    assert done.returncode == 0, done.stderr
    # The report reads results.csv and imports no plug-in, so it runs in this process: the same
    # command without a second interpreter importing the whole stack (≈ 2.7 s of CPU).
    report = CliRunner().invoke(app, ["campaign-report", str(out)])
    assert report.exit_code == 0, report.output
    return out


@pytest.mark.slow  # the campaign and its report: about 8 s, once for both
def test_the_plugin_rows_stand_beside_the_builtins_in_the_results(campaign: Path) -> None:
    rows = pd.read_csv(campaign / "results.csv")
    assert sorted(rows["config"]) == sorted(["GT", "L", "P", "F", SPEC])
    assert rows["error"].isna().all()
    plugin = rows[rows["config"] == SPEC].iloc[0]
    gt = rows[rows["config"] == "GT"].iloc[0]
    # Judged against the variant's GT run like any configuration: relative planned utilisation.
    key = "planned_utilization_at_comparison"
    assert plugin["utilization_vs_gt"] == pytest.approx(plugin[key] / gt[key] - 1.0, abs=1e-6)


@pytest.mark.slow  # the campaign and its report: about 8 s, once for both
def test_the_campaign_report_has_a_row_for_the_plugin(campaign: Path) -> None:
    report = (campaign / "report" / "report.md").read_text()
    for config in ("GT", "L", "P", "F", SPEC):
        assert any(line.startswith(f"| {config} ") for line in report.splitlines()), config


def test_the_readme_estimator_runs_on_the_sensor_frame(tmp_path: Path) -> None:
    import importlib.util
    import re

    import numpy as np

    from mufusion.configurations import step_source
    from mufusion.estimators import SensorModel

    readme = (ROOT / "README.md").read_text()
    section = readme[readme.index("## Your own estimator"):readme.index("## Documentation")]
    (code,) = re.findall(r"```python\n(.*?)```", section, re.S)
    assert len(code.splitlines()) <= 30
    path = tmp_path / "readme_estimators.py"
    path.write_text(code)
    spec = importlib.util.spec_from_file_location("readme_estimators", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    grid = np.arange(0.0, 61.0, 1.0)
    mu = np.where(grid < 30.0, 0.8, 0.4)
    estimate = step_source(module.CameraFloor(), SensorModel(), grid, mu, 0.7)
    # Measured under the vehicle (0.8 − 0.025 there), the class minima ahead (0.6 then 0.4),
    # the lowest class minimum seen beyond the camera's 50 m.
    assert estimate.mu_hat[0] == pytest.approx(0.775)
    assert estimate.mu_hat[10] == pytest.approx(0.6) and estimate.mu_hat[40] == pytest.approx(0.4)
    assert estimate.mu_hat[-1] == pytest.approx(0.4)
