"""`mufusion campaign` never loses a run: unique directories, all outputs under --out, failed runs
as rows, Ctrl-C writes a partial summary and says how to resume, --resume, --overwrite."""

from __future__ import annotations

import json
from importlib import resources
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

import mufusion.campaign.engines as engines
import mufusion.campaign.runs as runs_module
from mufusion.cli import app


def _campaign(out: Path, file: Path, *extra: str):
    return CliRunner().invoke(app, ["campaign", str(file), "--out", str(out), "--jobs", "1",
                                    *extra])


def _summary(out: Path) -> dict:
    return json.loads((out / "summary.json").read_text())


def _said(result) -> str:
    """The command's output with rich's line wrapping undone."""
    return " ".join(result.output.split())


def _tmp_leftovers(root: Path) -> list[Path]:
    return list(root.rglob(".tmp-*"))


def test_two_lateral_offsets_give_two_run_directories_and_two_rows(tmp_path, campaign_file):
    file = campaign_file('scenarios = ["popup"]\nconfigs = ["GT"]\n'
                         '[grid]\n"obstacle.lateral_offset_m" = [-1.0, 1.0]')
    out = tmp_path / "out"
    result = _campaign(out, file)
    assert result.exit_code == 0, result.output
    runs = _summary(out)["runs"]
    assert len(runs) == 2 and runs[0]["log"] != runs[1]["log"]
    for row, offset in zip(runs, (-1.0, 1.0), strict=True):
        meta = json.loads((out / row["log"] / "meta.json").read_text())
        assert meta["scenario_config"]["obstacle"]["lateral_offset_m"] == offset
        assert row["obstacle.lateral_offset_m"] == offset
    assert runs[0]["max_abs_lateral_offset_m"] != runs[1]["max_abs_lateral_offset_m"]
    table = pd.read_parquet(out / "results.parquet")
    assert table["obstacle.lateral_offset_m"].tolist() == [-1.0, 1.0]
    assert table["config"].tolist() == ["GT", "GT"] and table["error"].isna().all()
    assert pd.read_csv(out / "results.csv")["run"].tolist() == table["run"].tolist()
    assert not _tmp_leftovers(out)


def test_a_scenario_given_by_absolute_path_writes_only_under_out(tmp_path, campaign_file):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    scenario = elsewhere / "my popup.toml"
    scenario.write_text(resources.files("mufusion.scenarios").joinpath("popup.toml").read_text())
    file = campaign_file(f'scenarios = [{json.dumps(str(scenario.resolve()))}]\nconfigs = ["GT"]')
    out = tmp_path / "out"
    result = _campaign(out, file)
    assert result.exit_code == 0, result.output
    assert [p.name for p in elsewhere.iterdir()] == ["my popup.toml"]
    (run,) = _summary(out)["runs"]
    assert (out / run["log"]).is_dir() and run["log"] == "runs/0000-my_popup-default-GT"


def test_non_empty_out_is_refused_unless_overwrite_or_resume(tmp_path, campaign_file):
    file = campaign_file('scenarios = ["popup"]\nconfigs = ["GT"]')
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    result = _campaign(out, file)
    assert result.exit_code == 2 and "not empty" in _said(result)
    result = _campaign(out, file, "--overwrite")  # not a campaign directory: never cleared
    assert result.exit_code == 2 and "refusing to clear" in _said(result)
    assert (out / "notes.txt").read_text() == "mine"

    out = tmp_path / "campaign"
    assert _campaign(out, file).exit_code == 0
    assert _campaign(out, file).exit_code == 2  # a second campaign would mix files
    (out / "stale.png").write_text("old figure")
    result = _campaign(out, file, "--overwrite")
    assert result.exit_code == 0, result.output
    assert not (out / "stale.png").exists() and len(_summary(out)["runs"]) == 1
    result = _campaign(out, file, "--overwrite", "--resume")
    assert result.exit_code == 2 and "exclude each other" in _said(result)

    other = campaign_file('scenarios = ["popup"]\nconfigs = ["F"]', name="other.toml")
    result = _campaign(out, other, "--resume")
    assert result.exit_code == 2 and "different campaign" in _said(result)


def test_out_pointing_at_a_file_is_refused_before_anything_runs(tmp_path, campaign_file):
    file = campaign_file('scenarios = ["popup"]\nconfigs = ["GT"]')
    target = tmp_path / "a-file"
    target.write_text("")
    result = _campaign(target, file)
    assert result.exit_code == 2 and "is a file" in _said(result)


def test_a_failed_run_is_a_row_with_its_error_and_the_others_are_summarised(
    tmp_path, campaign_file, monkeypatch
):
    real = engines.run_scenario

    def fails_for_p(cfg, configuration, **kw):
        if configuration == "P":
            raise FloatingPointError("solver diverged")
        return real(cfg, configuration, **kw)

    monkeypatch.setattr(engines, "run_scenario", fails_for_p)
    file = campaign_file('scenarios = ["popup"]\nconfigs = ["GT", "P", "F"]')
    out = tmp_path / "out"
    result = _campaign(out, file)
    assert result.exit_code == 1, result.output
    assert "failed" in _said(result) and "solver diverged" in _said(result)
    summary = _summary(out)
    assert (summary["completed"], summary["failed"], summary["partial"]) == (2, 1, False)
    rows = {r["config"]: r for r in summary["runs"]}
    assert rows["P"]["error"] == "FloatingPointError: solver diverged" and rows["P"]["log"] is None
    assert rows["GT"]["error"] is None and rows["F"]["utilization_vs_gt"] is not None
    assert sorted(p.name for p in (out / "runs").iterdir()) == [
        "0000-popup-default-GT", "0002-popup-default-F"]
    table = pd.read_parquet(out / "results.parquet")
    assert table.set_index("config").loc["P", "error"] == "FloatingPointError: solver diverged"

    monkeypatch.setattr(engines, "run_scenario", real)  # --resume runs only the failed one
    result = _campaign(out, file, "--resume")
    assert result.exit_code == 0, result.output
    assert "2 found complete" in _said(result) and _summary(out)["failed"] == 0


def test_ctrl_c_writes_a_partial_summary_says_how_to_resume_and_resume_finishes(
    tmp_path, campaign_file, monkeypatch
):
    real = runs_module.publish_run
    published: list[Path] = []

    def interrupted_after_first(directory, files, result):
        if published:
            raise KeyboardInterrupt  # Ctrl-C while the parent stores the second run
        published.append(real(directory, files, result))
        return published[-1]

    monkeypatch.setattr(runs_module, "publish_run", interrupted_after_first)
    file = campaign_file('scenarios = ["popup"]\nconfigs = ["GT", "F"]\nseeds = 2')
    out = tmp_path / "out"
    result = _campaign(out, file)
    assert result.exit_code == 130, result.output
    assert "Resume with:" in _said(result) and "--resume" in _said(result)
    summary = _summary(out)
    assert summary["partial"] is True and summary["pending"] == 3
    assert [r["run"] for r in summary["runs"]] == ["0000-popup-default-s0-GT"]
    assert [p.name for p in (out / "runs").iterdir()] == ["0000-popup-default-s0-GT"]
    assert not _tmp_leftovers(out)
    first = (out / "runs" / "0000-popup-default-s0-GT" / "result.json").stat().st_mtime_ns

    monkeypatch.setattr(runs_module, "publish_run", real)
    result = _campaign(out, file, "--resume")
    assert result.exit_code == 0, result.output
    assert "1 found complete" in _said(result)
    summary = _summary(out)
    assert summary["partial"] is False and summary["completed"] == 4
    assert (out / "runs" / "0000-popup-default-s0-GT" / "result.json").stat().st_mtime_ns == first
    assert summary["runs"][1]["utilization_vs_gt"] is not None  # compared with the resumed GT


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (["--engine", "spark"], "--engine must be one of pool, ray"),
        (["--address", "10.0.0.1:6379"], "--address needs --engine ray"),
        (["--jobs", "0"], "--jobs must be >= 1"),
    ],
)
def test_bad_engine_options_exit_2(tmp_path, campaign_file, args, match):
    file = campaign_file('scenarios = ["popup"]\nconfigs = ["GT"]')
    result = CliRunner().invoke(app, ["campaign", str(file), "--out", str(tmp_path / "o"), *args])
    assert result.exit_code == 2 and match in _said(result)
