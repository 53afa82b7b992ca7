"""Running campaigns from the library: atomic run directories, Ctrl-C in the parent stops the
pool's workers and cancels the queue, a real SIGINT to `mufusion campaign`, run_campaign."""

from __future__ import annotations

import json
import multiprocessing
import os
import signal
import struct
import subprocess
import time
from pathlib import Path

import pytest

import mufusion.campaign.engines as engines
from mufusion.campaign import (
    CampaignInterrupted,
    RunSpec,
    execute_campaign,
    run_campaign,
)
from mufusion.campaign.storage import publish_run, read_result
from processes import isolated, mufusion_command, wait_until_session_empty

SHORT = ("duration_s=1.0",)


def _specs(n: int) -> list[RunSpec]:
    return [RunSpec("popup", "GT", f"seed {i}", overrides=SHORT, seed=i, index=i)
            for i in range(n)]


def test_publish_run_is_all_or_nothing(tmp_path):
    target = tmp_path / "runs" / "0000-x"
    with pytest.raises(FileNotFoundError):  # a file in a missing subdirectory: write fails
        publish_run(target, {"a.csv": b"1", "sub/b.csv": b"2"}, {"metrics": {}})
    assert not target.exists() and list((tmp_path / "runs").iterdir()) == []
    publish_run(target, {"a.csv": b"old", "stale.csv": b"x"}, {"n": 1})
    publish_run(target, {"a.csv": b"new"}, {"n": 2})  # replaces the earlier run whole
    assert sorted(p.name for p in target.iterdir()) == ["a.csv", "result.json"]
    assert (target / "a.csv").read_bytes() == b"new" and read_result(target) == {"n": 2}
    assert list((tmp_path / "runs").iterdir()) == [target]


def test_ctrl_c_in_the_parent_stops_the_pool_and_cancels_queued_runs(tmp_path):
    runs_dir = tmp_path / "runs"
    done: list[RunSpec] = []

    def interrupt_after_first(spec: RunSpec) -> None:
        done.append(spec)
        raise KeyboardInterrupt

    started = time.perf_counter()
    with pytest.raises(CampaignInterrupted) as stop:
        execute_campaign(_specs(8), runs_dir, jobs=2, on_done=interrupt_after_first)
    assert time.perf_counter() - started < 60.0
    assert len(done) == 1 and len(stop.value.finished) == 1 and len(stop.value.pending) == 7
    assert [p.name for p in runs_dir.iterdir()] == [done[0].name]
    # The workers are gone (active_children also reaps the ones that have just exited).
    deadline = time.monotonic() + 10.0
    while multiprocessing.active_children() and time.monotonic() < deadline:
        time.sleep(0.05)
    assert multiprocessing.active_children() == []
    time.sleep(2.0)  # and nothing queued starts later
    assert [p.name for p in runs_dir.iterdir()] == [done[0].name]


def test_stopping_the_pool_ends_a_manager_thread_stuck_on_a_partial_result():
    # What a worker terminated in the middle of sending its result leaves behind: a length
    # header promising 1 MB and three bytes of it. The executor's manager thread blocks reading
    # the rest; unless stopping the pool ends it, the interpreter's exit joins it for ever.
    from concurrent.futures import ProcessPoolExecutor

    pool = ProcessPoolExecutor(max_workers=1)
    pool.submit(time.sleep, 30.0)
    deadline = time.monotonic() + 10.0
    while not pool._processes and time.monotonic() < deadline:
        time.sleep(0.05)
    manager = pool._executor_manager_thread
    os.write(pool._result_queue._writer.fileno(), struct.pack("!i", 1_000_000) + b"abc")
    time.sleep(0.5)
    assert manager.is_alive()  # blocked on the partial message
    started = time.monotonic()
    engines._stop_pool(pool)
    manager.join(timeout=15.0)
    assert not manager.is_alive()
    assert time.monotonic() - started < 15.0
    assert multiprocessing.active_children() == []


def test_run_campaign_returns_triples_and_raises_naming_failed_runs(tmp_path, monkeypatch):
    specs = [RunSpec("popup", "GT", overrides=SHORT), RunSpec("popup", "F", overrides=SHORT)]
    results = run_campaign(specs, tmp_path / "a", jobs=1)
    assert [(s.config, d.name) for s, _m, d in results] == [
        ("GT", "0000-popup-default-GT"), ("F", "0001-popup-default-F")]
    assert results[1][1].utilization_vs_gt is not None

    def broken(cfg, configuration, **kw):
        raise RuntimeError("no solver")

    monkeypatch.setattr(engines, "run_scenario", broken)
    with pytest.raises(RuntimeError, match=r"2 of 2 runs failed: 0000-popup-default-GT: "
                                           r"RuntimeError: no solver"):
        run_campaign(specs, tmp_path / "b", jobs=1)
    with pytest.raises(ValueError, match="listed more than once"):
        run_campaign([specs[0], specs[0]], tmp_path / "c", jobs=1)


def _long_campaign(tmp_path) -> Path:
    """200 runs: more than can finish between the first published run and a signal, even on a
    fast machine (about 0.2 s per run on two cores here)."""
    file = tmp_path / "c.toml"
    file.write_text('scenarios = ["popup"]\nconfigs = ["GT", "F"]\nseeds = 100\n'
                    'overrides = ["duration_s=1.5", "estimation.local_error=random"]\n')
    return file


def _wait_for_a_published_run(proc: subprocess.Popen, out: Path) -> None:
    deadline = time.monotonic() + 120.0
    while time.monotonic() < deadline and proc.poll() is None:
        if (out / "runs").is_dir() and any(not p.name.startswith(".") for p in
                                           (out / "runs").iterdir()):
            # Signalled at once. The 2 s this wait used to add guarded against a signal landing
            # between a run directory's rename and the command's record of it (0 completed was
            # measured once); the command now lists a run it was publishing when it stopped
            # (test_a_signal_while_a_run_is_published_leaves_it_in_the_partial_summary).
            return
        time.sleep(0.05)


@pytest.mark.slow
def test_sigint_to_the_command_stops_it_with_a_partial_summary(tmp_path):
    out = tmp_path / "out"
    cmd = mufusion_command("campaign", str(_long_campaign(tmp_path)), "--out", str(out),
                           "--jobs", "2")
    with isolated(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True) as proc:
        _wait_for_a_published_run(proc, out)
        proc.send_signal(signal.SIGINT)
        output, _ = proc.communicate(timeout=60)
        assert proc.returncode == 130, output
        assert wait_until_session_empty(proc.pid, timeout_s=30.0) == []  # workers stopped
    summary = json.loads((out / "summary.json").read_text())
    assert summary["partial"] is True and 1 <= summary["completed"] < 200
    assert summary["completed"] + summary["pending"] == 200
    assert "--resume" in output
    names = sorted(p.name for p in (out / "runs").iterdir())
    assert names == sorted(r["run"] for r in summary["runs"])  # no half-written directory


def test_sigterm_in_the_parent_interrupts_like_ctrl_c_and_the_handler_is_restored(tmp_path):
    before = signal.getsignal(signal.SIGTERM)

    def terminated_after_first(spec: RunSpec) -> None:
        os.kill(os.getpid(), signal.SIGTERM)  # what a scheduler sends on preemption

    with pytest.raises(CampaignInterrupted) as stop:
        execute_campaign(_specs(3), tmp_path / "runs", jobs=1, on_done=terminated_after_first)
    assert stop.value.signal == signal.SIGTERM
    assert len(stop.value.finished) == 1 and len(stop.value.pending) == 2
    assert signal.getsignal(signal.SIGTERM) == before


@pytest.mark.slow
def test_sigterm_to_the_process_group_leaves_a_partial_summary_and_the_resume_command(tmp_path):
    # A cluster scheduler preempting the job signals every process of it: the command, its pool
    # workers. The workers must not die as failed runs; the command writes the summary.
    out = tmp_path / "out"
    cmd = mufusion_command("campaign", str(_long_campaign(tmp_path)), "--out", str(out),
                           "--jobs", "2")
    with isolated(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True) as proc:
        _wait_for_a_published_run(proc, out)
        signalled = time.monotonic()
        os.killpg(proc.pid, signal.SIGTERM)
        output, _ = proc.communicate(timeout=60)
        assert proc.returncode == 128 + signal.SIGTERM, output
        assert time.monotonic() - signalled < 30.0
        assert wait_until_session_empty(proc.pid, timeout_s=30.0) == []  # workers stopped
    said = " ".join(output.split())
    assert "interrupted (SIGTERM)" in said and "Resume with:" in said
    assert f"--out {out} --resume --jobs 2" in said
    summary = json.loads((out / "summary.json").read_text())
    assert summary["partial"] is True and summary["interrupted_by"] == "SIGTERM"
    assert 1 <= summary["completed"] < 200 and summary["failed"] == 0
    assert summary["completed"] + summary["pending"] == 200
    names = sorted(p.name for p in (out / "runs").iterdir())
    assert names == sorted(r["run"] for r in summary["runs"])  # no half-written directory


def test_a_signal_while_a_run_is_published_leaves_it_in_the_partial_summary(tmp_path,
                                                                             monkeypatch):
    # Ctrl-C between a run directory's rename and the command's record of it: the directory is
    # complete, so the interrupted campaign lists it (a resume would find it complete anyway).
    import mufusion.campaign.runs as runs_module

    publish = runs_module.publish_run

    def published_then_interrupted(*args, **kwargs):
        publish(*args, **kwargs)
        raise KeyboardInterrupt
    monkeypatch.setattr(runs_module, "publish_run", published_then_interrupted)
    with pytest.raises(CampaignInterrupted) as stop:
        execute_campaign(_specs(3), tmp_path / "runs", jobs=1)
    names = sorted(p.name for p in (tmp_path / "runs").iterdir())
    assert len(names) == 1 and [r.spec.name for r in stop.value.finished] == names
    assert stop.value.finished[0].metrics is not None and not stop.value.finished[0].resumed
    assert len(stop.value.pending) == 2
