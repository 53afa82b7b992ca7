"""A preempted `mufusion reproduce` (SIGTERM to its process group, as a cluster scheduler sends)
ends in bounded time with the runs it finished in a partial summary and a message, no traceback."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import time

import pytest

from mufusion.reproduction import reproduction_specs
from processes import isolated, mufusion_command, wait_until_session_empty


@pytest.mark.slow
def test_sigterm_leaves_a_partial_summary_and_says_so(tmp_path):
    out = tmp_path / "out"
    cmd = mufusion_command("reproduce", "--out", str(out), "--no-gif", "--no-car", "--jobs", "1")
    with isolated(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True) as proc:
        deadline = time.monotonic() + 120.0
        while time.monotonic() < deadline and proc.poll() is None and not (
                (out / "runs").is_dir() and any(not p.name.startswith(".")
                                                for p in (out / "runs").iterdir())):
            time.sleep(0.05)
        assert proc.poll() is None, "reproduce ended before it could be interrupted"
        signalled = time.monotonic()
        os.killpg(proc.pid, signal.SIGTERM)
        output, _ = proc.communicate(timeout=60)
        assert proc.returncode == 128 + signal.SIGTERM, output
        assert time.monotonic() - signalled < 30.0
        assert wait_until_session_empty(proc.pid, timeout_s=30.0) == []
    said = " ".join(output.split())
    assert "interrupted (SIGTERM)" in said and "Traceback" not in output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["partial"] is True and summary["interrupted_by"] == "SIGTERM"
    total = len(reproduction_specs(include_car=False))
    assert 1 <= len(summary["runs"]) < total
    assert len(summary["runs"]) + summary["pending"] == total
    assert all(run["config"] in {"GT", "L", "P", "F", "F-safe"} for run in summary["runs"])
