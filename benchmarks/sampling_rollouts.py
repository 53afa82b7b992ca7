"""Sampling roll-outs: CPU time per call of ``candidate_rollouts`` on the calls of a closed loop.

Run: ``python benchmarks/sampling_rollouts.py [--scenario popup] [--configuration F] [--rounds R]
[--calls N]``. One closed-loop run records every call the planner makes to ``candidate_rollouts``
(arguments and results). The recorded calls are then replayed: every result must come out bit for
bit as in the run (the script exits with an error otherwise), and the best of ``R`` rounds over
all calls gives the CPU time per call (``time.process_time``).

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
from mufusion.planner.sampling import candidate_rollouts
from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import run_scenario

Call = tuple[tuple[Any, ...], dict[str, Any], tuple[np.ndarray, np.ndarray]]


def record_calls(scenario: str, configuration: str) -> list[Call]:
    """Every ``candidate_rollouts`` call of one closed-loop run, with copies of its arrays."""
    calls: list[Call] = []
    original = planner_module.candidate_rollouts

    def recording(*args: Any, **kwargs: Any) -> tuple[np.ndarray, np.ndarray]:
        xs, us = original(*args, **kwargs)
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


def replay(calls: list[Call]) -> int:
    """Replay the calls; returns how many results differ bit for bit from the recorded ones."""
    differ = 0
    with np.errstate(all="ignore"):  # as the planner calls it: diverging candidates are kept
        for args, kwargs, (xs_run, us_run) in calls:
            xs, us = candidate_rollouts(*args, **kwargs)
            differ += xs.tobytes() != xs_run.tobytes() or us.tobytes() != us_run.tobytes()
    return differ


def best_cpu_s(calls: list[Call], rounds: int) -> float:
    """Best of ``rounds`` CPU times [s] for replaying all ``calls`` once."""
    best = float("inf")
    with np.errstate(all="ignore"):
        for _ in range(rounds):
            start = time.process_time()
            for args, kwargs, _ in calls:
                candidate_rollouts(*args, **kwargs)
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
    differ = replay(calls)
    if differ:
        sys.exit(f"{differ} of {len(calls)} replayed calls differ from the run")
    cpu_s = best_cpu_s(calls, args.rounds)
    print(json.dumps({
        "scenario": args.scenario,
        "configuration": args.configuration,
        "calls": len(calls),
        "rounds": args.rounds,
        "best_cpu_ms_all_calls": round(1e3 * cpu_s, 2),
        "cpu_ms_per_call": round(1e3 * cpu_s / len(calls), 3),
    }))


if __name__ == "__main__":
    main()
