"""Execution engines: where the runs of a campaign execute.

Every engine executes the same function, :func:`execute_run`, which loads the scenario, runs it,
computes its metrics and returns them with the log's files as bytes: the parent process writes
everything (atomically), so a worker that is stopped mid-run leaves nothing behind, and a Ray
worker on another machine needs no shared file system.

``pool``
    A :class:`~concurrent.futures.ProcessPoolExecutor` on this machine (one process per job;
    with one job the runs execute in this process).
``ray``
    Ray tasks: a local Ray instance with ``jobs`` CPUs, or the cluster at ``address``.

On Ctrl-C (``KeyboardInterrupt`` in the parent, also one raised by the ``handle`` callback, or
by the campaign's SIGTERM handler) an engine cancels the queued runs, stops the running ones and
re-raises. Pool workers ignore SIGINT and SIGTERM, which a terminal or a scheduler sends to the
whole process group: the parent decides, and stops them itself.
"""

from __future__ import annotations

import logging
import os
import signal
import socket
import tempfile
import threading
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

from mufusion._threads import one_blas_thread
from mufusion.campaign.schema import ENGINES, Engine
from mufusion.campaign.specs import RunSpec
from mufusion.metrics import RunMetrics, compute_metrics
from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import planner_for, run_scenario

_log = logging.getLogger(__name__)

RAY_CONNECT_TIMEOUT_S = 5.0
"""How long a Ray cluster's address may take to accept a connection before the campaign gives
up on it [s] (``ray.init`` itself retries an address where nothing answers for minutes)."""
RAY_INIT_TIMEOUT_S = 15.0
"""How long joining the cluster at an address that accepts connections may take [s] (a cluster
answers in seconds; something else listening there, or an address Ray rewrites to one it cannot
reach, kept ``ray.init`` retrying for minutes)."""


@dataclass(frozen=True)
class RunPayload:
    """What a worker sends back: the run's metrics and log files, or the error that ended it.

    Attributes
    ----------
    spec
        The run.
    metrics
        Its metrics (``None`` if it failed).
    files
        The log's files (name → contents), as :meth:`~mufusion.sim.log.RunLog.save` wrote them.
    error
        ``"<ExceptionType>: <message>"`` if the run raised, else ``None``.
    """

    spec: RunSpec
    metrics: RunMetrics | None
    files: dict[str, bytes]
    error: str | None = None


def execute_run(spec: RunSpec) -> RunPayload:
    """Run one spec and return its metrics and log files; never raises for a failing run.

    Exceptions become the payload's ``error`` (some, like LAPACK's, cannot be pickled across a
    process boundary). ``KeyboardInterrupt`` is not caught: it stops the campaign.
    """
    try:
        cfg = load_scenario(spec.scenario, spec.all_overrides)
        log = run_scenario(cfg, spec.config, planner=spec.planner, controller=spec.controller)
        metrics = compute_metrics(log)
        with tempfile.TemporaryDirectory(prefix="mufusion-run-") as tmp:
            log.save(tmp)
            files = {p.name: p.read_bytes() for p in sorted(Path(tmp).iterdir())}
    except Exception as exc:
        return RunPayload(spec, None, {}, f"{type(exc).__name__}: {exc}")
    return RunPayload(spec, metrics, files)


def warm_up_solvers(specs: Iterable[RunSpec]) -> None:
    """Build (or load from the cache) the planner of every vehicle the specs use, once, here,
    so that workers only load the compiled solvers."""
    seen = set()
    for spec in specs:
        cfg = load_scenario(spec.scenario, spec.all_overrides)
        key = (cfg.vehicle, cfg.planner.horizon_steps, cfg.planner.dt_s, cfg.planner.backend)
        if key not in seen:
            seen.add(key)
            planner_for(cfg)


def dispatch(
    specs: Sequence[RunSpec],
    handle: Callable[[RunPayload], None],
    *,
    engine: Engine = "pool",
    jobs: int | None = None,
    address: str | None = None,
) -> None:
    """Execute every spec on ``engine`` and call ``handle`` in this process as each finishes.

    Parameters
    ----------
    specs
        The runs, in the order they are submitted.
    handle
        Called with each run's payload, in completion order.
    engine
        ``"pool"`` or ``"ray"``.
    jobs
        Parallel runs (default: one per CPU core; a Ray cluster decides itself).
    address
        Ray cluster address (``ray`` only); default: start a local Ray instance.

    Raises
    ------
    ValueError
        If ``engine``, ``jobs`` or ``address`` is invalid, or Ray is not installed.
    KeyboardInterrupt
        After stopping the workers, if interrupted.
    """
    if engine not in ENGINES:
        raise ValueError(f"engine must be one of {list(ENGINES)}, got {engine!r}")
    if jobs is not None and jobs < 1:
        raise ValueError(f"jobs must be >= 1, got {jobs}")
    if address is not None and engine != "ray":
        raise ValueError("address is only used by the ray engine")
    if not specs:
        return
    workers = min(jobs or os.cpu_count() or 1, len(specs))
    if engine == "ray":
        _dispatch_ray(specs, handle, jobs=jobs, address=address)
    elif workers == 1:
        for spec in specs:
            handle(execute_run(spec))
    else:
        warm_up_solvers(specs)
        _dispatch_pool(specs, handle, workers)


def _set_up_worker(log_level: int) -> None:
    """Make a worker process behave like one core of this campaign."""
    # One BLAS thread per worker: OpenBLAS starts one per core in every process, and `jobs`
    # workers each spinning `cores` threads over-subscribe the machine (a 10-run pop-up
    # campaign, 2 jobs on 2 cores: 27–29 s with them, 12–23 s without). The libraries loaded
    # now are limited for the worker's life; each run limits them again, CasADi's among them
    # once a run has built a reference solver (mufusion._threads).
    one_blas_thread()  # applied at once, kept for the worker's life
    logging.getLogger("mufusion").setLevel(log_level)


def _pool_worker(log_level: int) -> None:
    # The parent decides what Ctrl-C and SIGTERM mean: it stops the workers itself (a worker
    # killed by a group-wide SIGTERM would turn its run into a failure instead of a pending one).
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    _set_up_worker(log_level)


def _ray_task(spec: RunSpec, log_level: int) -> RunPayload:
    _set_up_worker(log_level)
    return execute_run(spec)


def _parent_log_level() -> int:
    return logging.getLogger("mufusion").getEffectiveLevel()


def _dispatch_pool(
    specs: Sequence[RunSpec], handle: Callable[[RunPayload], None], workers: int
) -> None:
    pool = ProcessPoolExecutor(
        max_workers=workers, initializer=_pool_worker, initargs=(_parent_log_level(),)
    )
    try:
        futures: dict[Future[RunPayload], RunSpec] = {
            pool.submit(execute_run, spec): spec for spec in specs
        }
        for fut in as_completed(futures):
            try:
                payload = fut.result()
            except BrokenProcessPool as exc:  # a worker died (e.g. killed by the OS)
                payload = RunPayload(futures[fut], None, {}, f"BrokenProcessPool: {exc}")
            handle(payload)
    except BaseException:
        _stop_pool(pool)
        raise
    pool.shutdown(wait=True)


def _stop_pool(pool: ProcessPoolExecutor) -> None:
    """Cancel queued runs and terminate running workers."""
    # Python < 3.14 has no public call to stop running tasks (3.14: terminate_workers()).
    # The pool's process table is read before and after the shutdown request: the executor's
    # manager thread may drop it (or a process may appear) in between.
    processes = {p.pid: p for p in list((pool._processes or {}).values())}
    # The shutdown request drops these references; the manager thread keeps using them.
    # (typeshed types the manager thread as the wake-up helper and hides the queue's writer.)
    manager = cast("threading.Thread | None", pool._executor_manager_thread)
    result_queue: Any = pool._result_queue
    pool.shutdown(wait=False, cancel_futures=True)
    processes.update({p.pid: p for p in list((pool._processes or {}).values())})
    # SIGKILL: the workers ignore SIGTERM, and they hold nothing to clean up (the parent
    # writes every file).
    for process in processes.values():
        if process.is_alive():
            process.kill()
    for process in processes.values():
        process.join(timeout=10.0)
    # A worker terminated while sending its result leaves a partial message in the result
    # pipe: the executor's manager thread then blocks reading the rest, and the interpreter's
    # exit, which joins that thread, hangs. With the workers gone the parent holds the pipe's
    # last write end; closing it turns the partial read into end-of-file, which the thread
    # takes for a broken pool and ends on. (CPython 3.11-3.13 internals, as _processes above.)
    if result_queue is not None:
        result_queue._writer.close()
    if manager is not None:
        manager.join(timeout=10.0)


def check_reachable(address: str, timeout_s: float = RAY_CONNECT_TIMEOUT_S) -> None:
    """Raise ``ValueError`` naming ``address`` if nothing accepts a connection at its host and
    port within ``timeout_s``.

    ``address`` is a Ray cluster address, ``host:port`` or ``ray://host:port``; one without a
    port (Ray's ``"auto"``) is left to Ray.

    Examples
    --------
    >>> check_reachable("127.0.0.1:9", timeout_s=1.0)  # the discard port: nothing listens
    Traceback (most recent call last):
    ...
    ValueError: no Ray cluster answers at '127.0.0.1:9' ...
    """
    host, sep, port = address.removeprefix("ray://").rpartition(":")
    if not sep or not port.isdigit():
        return
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout_s):
            pass
    except OSError as err:
        raise ValueError(
            f"no Ray cluster answers at {address!r} (connecting to {host}:{port}: "
            f"{err.strerror or err}); check --address and that the cluster is up"
        ) from None


def _init_ray(ray: Any, address: str | None, num_cpus: int | None) -> None:
    """``ray.init``, bounded in time when joining a cluster at ``address``; this process's
    SIGTERM handler is left as it was (Ray's would end the process without the campaign's
    partial summary).

    Raises
    ------
    ValueError
        If the cluster at ``address`` was not joined within :data:`RAY_INIT_TIMEOUT_S`.
    """
    previous = signal.getsignal(signal.SIGTERM)

    def init() -> None:
        ray.init(address=address, num_cpus=num_cpus, include_dashboard=False,
                 logging_level=logging.WARNING)

    try:
        if address is None:
            init()
            return
        # In a thread, which the command can leave behind: ray.init has no timeout of its own.
        # Outside the main thread Ray sets no SIGTERM handler and says so; that note is dropped.
        quiet = _DropMessage("SIGTERM handler is not set")
        logging.getLogger("ray._private.worker").addFilter(quiet)
        failure: list[BaseException] = []
        joining = threading.Thread(target=_capture_failure(init, failure), daemon=True)
        joining.start()
        joining.join(RAY_INIT_TIMEOUT_S)
        logging.getLogger("ray._private.worker").removeFilter(quiet)
        if joining.is_alive():
            raise ValueError(
                f"no Ray cluster answered at {address!r} within {RAY_INIT_TIMEOUT_S:g} s "
                "(something accepts connections there, but it did not let this process join); "
                "check --address and that the cluster is up"
            )
        if failure:
            raise failure[0]
    finally:
        if threading.current_thread() is threading.main_thread() and previous is not None:
            signal.signal(signal.SIGTERM, previous)


def _capture_failure(call: Callable[[], None], failure: list[BaseException]) -> Callable[[], None]:
    def run() -> None:
        try:
            call()
        except BaseException as exc:  # handed to the waiting thread
            failure.append(exc)

    return run


class _DropMessage(logging.Filter):
    """Drops the log records whose message starts with ``start``."""

    def __init__(self, start: str) -> None:
        super().__init__()
        self.start = start

    def filter(self, record: logging.LogRecord) -> bool:
        return not record.getMessage().startswith(self.start)


def _dispatch_ray(
    specs: Sequence[RunSpec],
    handle: Callable[[RunPayload], None],
    *,
    jobs: int | None,
    address: str | None,
) -> None:
    try:
        import ray
    except ImportError:
        raise ValueError(
            "the ray engine needs Ray: pip install 'mufusion[scale]' (install.sh does)"
        ) from None
    started = not ray.is_initialized()
    if started:
        if address is not None:
            check_reachable(address)
        if address is None:
            warm_up_solvers(specs)  # the local workers share this machine's solver cache
        try:
            _init_ray(ray, address, None if address else (jobs or os.cpu_count() or 1))
        except (ConnectionError, RuntimeError, ValueError) as err:
            raise ValueError(f"cannot start or reach Ray (address={address!r}): {err}") from None
    task = ray.remote(num_cpus=1, max_retries=0)(_ray_task)
    level = _parent_log_level()
    pending = {task.remote(spec, level): spec for spec in specs}
    try:
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            for ref in done:
                spec = pending.pop(ref)
                try:
                    payload = ray.get(ref)
                except ray.exceptions.RayError as exc:  # the worker died or was lost
                    payload = RunPayload(spec, None, {}, f"{type(exc).__name__}: {exc}")
                handle(payload)
    except BaseException:
        # A local instance we started goes down with ray.shutdown() below, workers and all.
        # Force-cancelling its tasks first raced with tasks finishing at that moment: Ray's core
        # worker then failed an internal check ("Tried to complete task that was not pending")
        # and took this process down with exit code 1 (seen once in CI on Ctrl-C). A cluster we
        # joined outlives us, so there the runs still queued or running are cancelled; those
        # already finished are left alone (the race remains only for one finishing meanwhile).
        if not started and pending:
            ready, _ = ray.wait(list(pending), num_returns=len(pending), timeout=0)
            for ref in set(pending) - set(ready):
                ray.cancel(ref, force=True)
        raise
    finally:
        if started:
            ray.shutdown()
