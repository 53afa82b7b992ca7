"""Running a campaign: check the runs, skip the complete ones, dispatch the rest to an engine,
store each result atomically as it arrives, and hand back every finished run.

Nothing is lost: a failing run becomes a result with its error while the others go on; on Ctrl-C
(SIGINT) or SIGTERM (what a cluster scheduler sends on preemption, or ``kill``) the engine stops
its workers and :class:`CampaignInterrupted` carries what finished, so the caller can still write
the summary and a later call with ``resume=True`` picks up from there.
"""

from __future__ import annotations

import json
import signal
import threading
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

from mufusion.campaign.engines import RunPayload, dispatch
from mufusion.campaign.results import RunResult, with_gt_comparison
from mufusion.campaign.schema import Engine
from mufusion.campaign.specs import RunSpec, check_distinct, with_indices
from mufusion.campaign.storage import publish_run, read_result, remove_temporaries
from mufusion.metrics import RunMetrics
from mufusion.scenarios import load_scenario


class CampaignInterrupted(KeyboardInterrupt):
    """A signal stopped a campaign; ``finished`` holds the runs that completed or failed before
    it (GT comparison filled in), ``pending`` the ones that did not run and ``signal`` the
    signal (``SIGINT`` for Ctrl-C, or ``SIGTERM``)."""

    def __init__(self, finished: list[RunResult], pending: list[RunSpec],
                 signal: signal.Signals = signal.SIGINT):
        super().__init__(f"campaign interrupted by {signal.name}: {len(finished)} runs "
                         f"finished, {len(pending)} did not run")
        self.finished = finished
        self.pending = pending
        self.signal = signal


class _Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread where Ctrl-C raises ``KeyboardInterrupt``."""


@contextmanager
def _sigterm_stops_like_ctrl_c() -> Iterator[None]:
    """While active, SIGTERM raises :class:`_Terminated` in the main thread (once: a repeat while
    the workers are being stopped is ignored), so it ends a campaign as Ctrl-C does."""
    if threading.current_thread() is not threading.main_thread():
        yield  # signal handlers can only be set in the main thread
        return

    def terminate(_signum: int, _frame: object) -> None:
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        raise _Terminated

    previous = signal.signal(signal.SIGTERM, terminate)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def spec_record(spec: RunSpec) -> dict[str, Any]:
    """The spec as stored in its ``result.json`` (compared on resume).

    Plug-in fields left at None are not stored: a run stored before they existed still matches.
    """
    record = asdict(spec)
    for key in ("planner", "controller"):
        if record[key] is None:
            del record[key]
    return json.loads(json.dumps(record))


def execute_campaign(
    specs: Sequence[RunSpec],
    runs_dir: Path,
    *,
    engine: Engine = "pool",
    jobs: int | None = None,
    address: str | None = None,
    resume: bool = False,
    on_done: Callable[[RunSpec], None] | None = None,
) -> list[RunResult]:
    """Run every spec, each into ``runs_dir/<spec.name>``, and return the results in spec order.

    Parameters
    ----------
    specs
        The runs (indices are assigned from their positions where missing).
    runs_dir
        Directory of the run directories (created if needed).
    engine, jobs, address
        Where the runs execute (:func:`mufusion.campaign.engines.dispatch`).
    resume
        Skip runs whose directory is complete and holds the same spec; their stored metrics are
        used. Other runs (missing, failed, incomplete) run again.
    on_done
        Called in this process after each run finishes (also for skipped ones).

    Returns
    -------
    list of RunResult
        Completed and failed runs, in the order of ``specs``, with ``utilization_vs_gt`` from the
        GT run of the same scenario, variant and seed where the campaign has one.

    Raises
    ------
    ValueError
        If ``jobs`` < 1, two specs are the same run, or a spec names an unknown scenario,
        configuration or key (checked before anything runs).
    CampaignInterrupted
        On Ctrl-C (SIGINT) or SIGTERM, after the workers stopped; it carries the finished runs
        and the signal.
    """
    specs = with_indices(specs)
    check_distinct(specs)
    seeds = {spec: load_scenario(spec.scenario, spec.all_overrides).seed for spec in specs}
    runs_dir.mkdir(parents=True, exist_ok=True)
    remove_temporaries(runs_dir)
    results: dict[RunSpec, RunResult] = {}
    # The run being published: a signal between its directory's rename and its entry in
    # ``results`` would leave a complete directory the summary does not list.
    publishing: list[RunSpec] = []

    def store(payload: RunPayload) -> None:
        spec = payload.spec
        directory = None
        if payload.metrics is not None:
            record = {"spec": spec_record(spec), "seed": seeds[spec],
                      "metrics": payload.metrics.to_dict()}
            publishing.append(spec)
            directory = publish_run(runs_dir / spec.name, payload.files, record)
        results[spec] = RunResult(spec, seeds[spec], _stored(payload.metrics), payload.error,
                                  directory)
        publishing.clear()
        if on_done:
            on_done(spec)

    try:
        with _sigterm_stops_like_ctrl_c():
            if resume:
                for spec in specs:
                    found = _completed_run(runs_dir / spec.name, spec, seeds[spec])
                    if found is not None:
                        results[spec] = found
                        if on_done:
                            on_done(spec)
            todo = [s for s in specs if s not in results]
            dispatch(todo, store, engine=engine, jobs=jobs, address=address)
    except KeyboardInterrupt as stop:
        remove_temporaries(runs_dir)
        for spec in publishing:
            found = _completed_run(runs_dir / spec.name, spec, seeds[spec])
            if spec not in results and found is not None:
                results[spec] = replace(found, resumed=False)
        finished = with_gt_comparison(results[s] for s in specs if s in results)
        raise CampaignInterrupted(
            finished, [s for s in specs if s not in results],
            signal.SIGTERM if isinstance(stop, _Terminated) else signal.SIGINT,
        ) from None
    return with_gt_comparison(results[s] for s in specs)


def _stored(metrics: RunMetrics | None) -> RunMetrics | None:
    # Metrics as result.json stores them (rounded to 1e-6), so that a resumed campaign reports
    # exactly what an uninterrupted one does.
    return None if metrics is None else RunMetrics(**metrics.to_dict())


def _completed_run(directory: Path, spec: RunSpec, seed: int) -> RunResult | None:
    record = read_result(directory)
    if record is None or record.get("spec") != spec_record(spec):
        return None
    try:
        metrics = RunMetrics(**record["metrics"])
    except (KeyError, TypeError):  # written by a version with other metrics: run it again
        return None
    return RunResult(spec, seed, metrics, None, directory, resumed=True)


def run_campaign(
    specs: Sequence[RunSpec],
    out_root: Path,
    *,
    jobs: int | None = None,
    on_done: Callable[[RunSpec], None] | None = None,
) -> list[tuple[RunSpec, RunMetrics, Path]]:
    """Run every spec in a process pool and return ``(spec, metrics, directory)`` in spec order.

    The short form of :func:`execute_campaign` for callers that need every run to succeed
    (``mufusion reproduce``): runs go to ``out_root/<spec.name>``, replacing earlier ones.

    Raises
    ------
    ValueError
        If ``jobs`` < 1, two specs are the same run, or a spec is invalid.
    RuntimeError
        If runs failed (after all the others finished and were saved), naming each one.
    """
    results = execute_campaign(specs, out_root, jobs=jobs, on_done=on_done)
    failures = [f"{r.spec.name}: {r.error}" for r in results if r.error is not None]
    if failures:
        raise RuntimeError(f"{len(failures)} of {len(results)} runs failed: " + "; ".join(failures))
    return [(r.spec, r.metrics, r.directory) for r in results
            if r.metrics is not None and r.directory is not None]
