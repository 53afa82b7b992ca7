"""Same seeds, same results, whichever engine runs them: the process pool and a local Ray."""

from __future__ import annotations

import json
import signal
import socket
import subprocess
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from mufusion.campaign.engines import RAY_INIT_TIMEOUT_S, check_reachable, dispatch
from mufusion.campaign.stats import WALL_CLOCK_SUFFIX
from mufusion.sim.log import STAMPS_KEY
from processes import command_lines, isolated, mufusion_command, wait_until_session_empty

CAMPAIGN = """
scenarios = ["popup"]
configs = ["F"]
seeds = 3
overrides = ["duration_s=1.5", "estimation.local_error=random",
             "estimation.predictive_error=random"]
"""


def _metrics(directory: Path) -> dict:
    metrics = json.loads((directory / "result.json").read_text())["metrics"]
    return {k: v for k, v in metrics.items() if not k.endswith(WALL_CLOCK_SUFFIX)}


def _log_files(directory) -> dict[str, bytes]:
    # timing.csv holds wall-clock times, the one part of a log that is not deterministic (and so
    # is its checksum in meta.json); result.json holds the metrics, compared above without the
    # timings.
    skip = {"timing.csv", "result.json"}
    files = {p.name: p.read_bytes() for p in directory.iterdir() if p.name not in skip}
    meta = json.loads(files.pop("meta.json"))
    del meta[STAMPS_KEY]["timing.csv"]
    return {**files, "meta.json": json.dumps(meta).encode()}


def _run_directories(out: Path) -> dict[str, Path]:
    return {p.name: p for p in (out / "runs").iterdir()}


def _campaign(tmp_path: Path, seeds: int) -> Path:
    path = tmp_path / "c.toml"
    path.write_text(CAMPAIGN.replace("seeds = 3", f"seeds = {seeds}"))
    return path


NO_CLUSTER_TEST = "test_an_address_that_accepts_connections_but_is_no_cluster_fails_in_bounded_time"


@dataclass
class BackgroundCampaign:
    """A campaign command started in the background; ``done`` is set when it has exited."""

    address: str
    proc: subprocess.Popen
    started: float
    done: threading.Event = field(default_factory=threading.Event)
    output: str = ""
    elapsed_s: float = float("nan")  # from its start to its exit


@pytest.fixture(scope="module", autouse=True)
def no_cluster_campaign(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory,
) -> Iterator[BackgroundCampaign | None]:
    """The campaign of :data:`NO_CLUSTER_TEST`, started as this module starts.

    That command waits out the join's bound (``RAY_INIT_TIMEOUT_S``, 15 s) doing nothing; started
    here it waits while the module's other tests run, and the test collects its exit, timed
    from its start to its exit, as it would have timed it alone. Not started when that test is not
    selected (``-m 'not slow'``, ``-k``).
    """
    if not any(item.name == NO_CLUSTER_TEST for item in request.session.items):
        yield None
        return
    tmp_path = tmp_path_factory.mktemp("no_cluster")
    # Something listens there (and Ray rewrites a loopback address to the node's own, where
    # nothing does): ray.init alone retried for minutes.
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        address = f"127.0.0.1:{server.getsockname()[1]}"
        cmd = mufusion_command("campaign", str(_campaign(tmp_path, seeds=2)), "--out",
                               str(tmp_path / "out"), "--engine", "ray", "--address", address)
        started = time.monotonic()
        with isolated(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True) as proc:
            run = BackgroundCampaign(address, proc, started)

            def wait() -> None:
                run.output, _ = proc.communicate()
                run.elapsed_s = time.monotonic() - run.started
                run.done.set()

            threading.Thread(target=wait, daemon=True).start()
            yield run  # leaving ``isolated`` kills whatever of it is left


# Ray runs in a child process in its own session: the local instance's raylet, GCS and workers
# are then the command's to start and stop, and the test can check that none of them outlives it.
@pytest.mark.slow
def test_pool_and_local_ray_give_identical_runs_for_the_same_seeds(tmp_path):
    path = _campaign(tmp_path, seeds=3)
    outs = {}
    for engine in ("pool", "ray"):
        outs[engine] = tmp_path / engine
        cmd = mufusion_command("campaign", str(path), "--out", str(outs[engine]), "--jobs", "2",
                               "--engine", engine)
        with isolated(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True) as proc:
            output, _ = proc.communicate(timeout=300)
            assert proc.returncode == 0, output
            assert wait_until_session_empty(proc.pid, timeout_s=30.0) == []
    pool, ray = (_run_directories(outs[e]) for e in ("pool", "ray"))
    assert sorted(pool) == sorted(ray) and len(pool) == 3
    for name in pool:
        assert _log_files(pool[name]) == _log_files(ray[name]), name
        assert _metrics(pool[name]) == _metrics(ray[name]), name
    # The seeds reach the random error models: different seeds, different estimates.
    estimates = {(d / "estimates.csv").read_bytes() for d in pool.values()}
    assert len(estimates) == 3


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"engine": "dask"}, "engine must be one of"),
        ({"jobs": 0}, "jobs must be >= 1"),
        ({"address": "10.0.0.1:6379"}, "address is only used by the ray engine"),
    ],
)
def test_dispatch_rejects_bad_options(kwargs, match):
    with pytest.raises(ValueError, match=match):
        dispatch([], print, **kwargs)


@pytest.mark.slow
def test_sigint_stops_a_ray_campaign_and_its_local_instance(tmp_path):
    out = tmp_path / "out"
    cmd = mufusion_command("campaign", str(_campaign(tmp_path, seeds=40)), "--out", str(out),
                           "--jobs", "2", "--engine", "ray")
    with isolated(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True) as proc:
        deadline = time.monotonic() + 180.0
        while time.monotonic() < deadline and proc.poll() is None:
            if (out / "runs").is_dir() and any(not p.name.startswith(".")
                                               for p in (out / "runs").iterdir()):
                break
            time.sleep(0.05)
        proc.send_signal(signal.SIGINT)
        output, _ = proc.communicate(timeout=120)
        assert proc.returncode == 130, output
        # The local Ray instance (raylet, GCS, workers) went down with the command. Its
        # teardown is asynchronous (the raylet reaps its workers after the driver has gone):
        # on a loaded 2-core machine one process once outlived 30 s, so it gets 60 s.
        left = wait_until_session_empty(proc.pid, timeout_s=60.0)
        assert left == [], (output, command_lines(left))
    summary = json.loads((out / "summary.json").read_text())
    assert summary["partial"] is True and 1 <= summary["completed"] < 40
    assert summary["completed"] + summary["pending"] == 40
    assert "--resume" in output
    assert sorted(_run_directories(out)) == sorted(r["run"] for r in summary["runs"])


def test_a_listening_address_is_reachable_and_a_closed_one_is_named(tmp_path):
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        port = server.getsockname()[1]
        check_reachable(f"127.0.0.1:{port}", timeout_s=5.0)
        check_reachable(f"ray://127.0.0.1:{port}", timeout_s=5.0)
    with pytest.raises(ValueError, match=f"no Ray cluster answers at '127.0.0.1:{port}'"):
        check_reachable(f"127.0.0.1:{port}", timeout_s=5.0)  # closed now


def test_a_ray_address_where_nothing_answers_fails_in_bounded_time_naming_it(tmp_path):
    out = tmp_path / "out"
    cmd = mufusion_command("campaign", str(_campaign(tmp_path, seeds=2)), "--out", str(out),
                           "--engine", "ray", "--address", "127.0.0.1:9")  # discard: closed
    started = time.monotonic()
    with isolated(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True) as proc:
        output, _ = proc.communicate(timeout=60)
    assert time.monotonic() - started < 30.0, output
    assert proc.returncode == 2, output
    assert "no Ray cluster answers at '127.0.0.1:9'" in " ".join(output.split())


@pytest.mark.slow
def test_an_address_that_accepts_connections_but_is_no_cluster_fails_in_bounded_time(
    no_cluster_campaign: BackgroundCampaign | None,
):
    # The command started with the module (no_cluster_campaign): it has waited meanwhile.
    run = no_cluster_campaign
    assert run is not None
    assert run.done.wait(timeout=max(0.0, run.started + 90.0 - time.monotonic())), \
        "the command was still running after 90 s"
    output = run.output
    assert run.proc.returncode == 2, output
    assert run.elapsed_s < RAY_INIT_TIMEOUT_S + 20.0, output  # the join's bound plus start-up
    assert f"no Ray cluster answered at '{run.address}'" in " ".join(output.split())
