"""Sampling roll-outs: CPU time per call of ``candidate_rollouts`` on the calls of a closed loop,
the compiled loop against the numpy one.

Run: ``python benchmarks/sampling_rollouts.py [--scenario popup] [--configuration F] [--rounds R]
[--calls N]``. One closed-loop run records every call the planner makes to ``candidate_rollouts``
(arguments and results, computed with numpy). The recorded calls are then replayed with each
kind: every result must come out as in the run (numpy: bit for bit; compiled: bit for bit except
a NaN's sign and payload, in the candidates that diverged; the script exits with an error
otherwise), and the best of ``R`` rounds over all calls gives each kind's CPU time per call
(``time.process_time``) and their ratio.

``--calls N`` replays ``N`` calls instead (cycling through the recorded ones), once and untimed,
for an instruction count that the load of a shared machine does not move: run the script under
``valgrind --tool=cachegrind --cache-sim=no`` with ``--calls 0`` and ``--calls 200``; the
difference of the two counts over 200 is the count per call. Numbers go to docs/performance.md,
section "## Closed loop".
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from typing import Any

import numpy as np

import mufusion.planner.planner as planner_module
from mufusion.planner.sampling import candidate_rollouts, compiled_rollouts_available
from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import run_scenario

Call = tuple[tuple[Any, ...], dict[str, Any], tuple[np.ndarray, np.ndarray]]


def record_calls(scenario: str, configuration: str) -> list[Call]:
    """Every ``candidate_rollouts`` call of one closed-loop run, with copies of its arrays."""
    calls: list[Call] = []
    original = planner_module.candidate_rollouts

    def recording(*args: Any, **kwargs: Any) -> tuple[np.ndarray, np.ndarray]:
        xs, us = original(*args, **{**kwargs, "kind": "numpy"})
        # The loop may reuse its arrays, and the planner keeps a slice of the result.
        frozen = tuple(a.copy() if isinstance(a, np.ndarray) else a for a in args)
        calls.append((frozen, dict(kwargs), (xs.copy(), us.copy())))
        return xs, us

    planner_module.candidate_rollouts = recording
    try:
        run_scenario(load_scenario(scenario), configuration)
    finally:
        planner_module.candidate_rollouts = original
    return calls


def _bytes(a: np.ndarray, canonical_nan: bool) -> bytes:
    return (np.where(np.isnan(a), np.nan, a) if canonical_nan else a).tobytes()


def replay(calls: list[Call], kind: str = "numpy") -> int:
    """Replay the calls with ``kind``; returns how many results differ from the recorded ones."""
    differ = 0
    nan = kind != "numpy"
    with np.errstate(all="ignore"):  # as the planner calls it: diverging candidates are kept
        for args, kwargs, (xs_run, us_run) in calls:
            xs, us = candidate_rollouts(*args, **{**kwargs, "kind": kind})
            differ += (_bytes(xs, nan) != _bytes(xs_run, nan)
                       or _bytes(us, nan) != _bytes(us_run, nan))
    return differ


def best_cpu_s(calls: list[Call], rounds: int, kind: str) -> float:
    """Best of ``rounds`` CPU times [s] for replaying all ``calls`` once with ``kind``."""
    best = float("inf")
    with np.errstate(all="ignore"):
        for _ in range(rounds):
            start = time.process_time()
            for args, kwargs, _ in calls:
                candidate_rollouts(*args, **{**kwargs, "kind": kind})
            best = min(best, time.process_time() - start)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="popup", help="built-in scenario (popup or turn)")
    parser.add_argument("--configuration", default="F", help="friction configuration")
    parser.add_argument("--rounds", type=int, default=7, help="timed rounds over all calls (≥ 1)")
    parser.add_argument("--calls", type=int, default=None,
                        help="replay this many calls once, untimed (≥ 0; for instruction counts)")
    args = parser.parse_args()
    if args.rounds < 1:
        raise ValueError(f"--rounds must be >= 1, got {args.rounds}")
    if args.calls is not None and args.calls < 0:
        raise ValueError(f"--calls must be >= 0, got {args.calls}")
    calls = record_calls(args.scenario, args.configuration)
    if not calls:
        sys.exit(f"{args.scenario} ({args.configuration}) never samples: nothing to time")
    if args.calls is not None:
        replay([calls[i % len(calls)] for i in range(args.calls)])
        return
    kinds = ("numpy", "compiled") if compiled_rollouts_available() else ("numpy",)
    result: dict[str, Any] = {
        "scenario": args.scenario,
        "configuration": args.configuration,
        "calls": len(calls),
        "rounds": args.rounds,
    }
    for kind in kinds:
        differ = replay(calls, kind)
        if differ:
            sys.exit(f"{differ} of {len(calls)} calls replayed with {kind} differ from the run")
        cpu_s = best_cpu_s(calls, args.rounds, kind)
        result[f"{kind}_cpu_ms_per_call"] = round(1e3 * cpu_s / len(calls), 3)
    if len(kinds) == 2:
        result["ratio_compiled_to_numpy"] = round(
            result["compiled_cpu_ms_per_call"] / result["numpy_cpu_ms_per_call"], 3)
    print(json.dumps(result))


if __name__ == "__main__":
    main()
