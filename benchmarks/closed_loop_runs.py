"""Run one paper scenario once (solver loaded, caches warm) and then N more times.

BLAS pools are limited to one thread (as ``run_scenario`` does itself; older code did not).

For counts that do not depend on other jobs on the machine: under valgrind, the difference
between N = 2 and N = 0, halved, is the instructions of one run::

    PYTHONHASHSEED=0 valgrind --tool=cachegrind --cache-sim=no \\
        python benchmarks/closed_loop_runs.py turn 2

Run: ``python benchmarks/closed_loop_runs.py {turn,popup} N [--configuration F]``.
"""

from __future__ import annotations

import argparse

from threadpoolctl import threadpool_limits

from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import run_scenario


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", choices=("turn", "popup"))
    parser.add_argument("runs", type=int, help="runs after the first (≥ 0)")
    parser.add_argument("--configuration", default="F", help="friction configuration")
    args = parser.parse_args()
    if args.runs < 0:
        raise ValueError(f"runs must be >= 0, got {args.runs}")
    cfg = load_scenario(args.scenario)
    with threadpool_limits(limits=1, user_api="blas"):
        for _ in range(1 + args.runs):
            run_scenario(cfg, args.configuration)


if __name__ == "__main__":
    main()
