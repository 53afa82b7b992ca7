"""Path projection: CPU time per warm-started Newton projection of the closed loop's points, the
compiled frame and Newton step against the Python ones.

Run: ``python benchmarks/path_projection.py [--scenario turn] [--configuration F]
[--rounds R]``. One closed-loop run (the paper's method) records every Newton projection the
loop makes (the centre of gravity, the axles, the footprint's centre and corners: point, start
and iteration limit). The recorded projections are then replayed through both
implementations; every result must come out bit for bit as in the run (the script exits with an
error otherwise), and the best of ``R`` rounds gives each one's CPU time per projection
(``time.process_time``) and their ratio. Numbers go to docs/performance.md, section
"## Closed loop".
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable
from typing import Any

from mufusion.reproduction.variants import PAPER_METHOD
from mufusion.road.path import ReferencePath, compiled_frames_available
from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import run_scenario

Call = tuple[float, float, float, int]


def record_calls(scenario: str, configuration: str) -> tuple[ReferencePath, list[Call], list]:
    """The run's road, every Newton projection it made, and each one's result."""
    calls: list[Call] = []
    results: list = []
    paths: list[tuple[ReferencePath, Callable[..., Any]]] = []
    original_init = ReferencePath.__init__

    def recording_init(self: ReferencePath, *args: Any, **kwargs: Any) -> None:
        original_init(self, *args, **kwargs)
        newton = self._newton_scalar

        def recording(px: float, py: float, s: float, iterations: int) -> Any:
            result = newton(px, py, s, iterations)
            calls.append((px, py, s, iterations))
            results.append(result)
            return result

        self._newton_scalar = recording
        paths.append((self, newton))

    ReferencePath.__init__ = recording_init  # type: ignore[method-assign]
    try:
        run_scenario(load_scenario(scenario, list(PAPER_METHOD)), configuration)
    finally:
        ReferencePath.__init__ = original_init  # type: ignore[method-assign]
    if not calls:
        raise SystemExit("the run made no projection")
    for path, newton in paths:
        path._newton_scalar = newton  # type: ignore[method-assign]
    return paths[-1][0], calls, results


def _time(newton: Callable[[float, float, float, int], Any], calls: list[Call]) -> float:
    start = time.process_time()
    for px, py, s, iterations in calls:
        newton(px, py, s, iterations)
    return (time.process_time() - start) / len(calls)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="turn", choices=("turn", "popup"))
    parser.add_argument("--configuration", default="F")
    parser.add_argument("--rounds", type=int, default=7, help="timed rounds (≥ 1)")
    args = parser.parse_args()
    if args.rounds < 1:
        parser.error("--rounds must be ≥ 1")
    if not compiled_frames_available():
        raise SystemExit("the compiled frames are not built (pip install -e .)")
    path, calls, results = record_calls(args.scenario, args.configuration)
    kinds = {"python": path._newton_python, "compiled": path._newton_scalar}
    for kind, newton in kinds.items():
        for call, want in zip(calls, results, strict=True):
            if repr(newton(*call)) != repr(want):
                sys.exit(f"{kind}: projection {call} differs from the run's")
    best = {kind: float("inf") for kind in kinds}
    for _ in range(args.rounds):  # interleaved, so that drift hits both alike
        for kind, newton in kinds.items():
            best[kind] = min(best[kind], _time(newton, calls))
    ratio = best["compiled"] / best["python"]
    print(f"{args.scenario} ({args.configuration}, paper's method): {len(calls)} projections; "
          f"python {1e6 * best['python']:.2f} µs, compiled {1e6 * best['compiled']:.2f} µs "
          f"per projection (best of {args.rounds}); ratio {ratio:.2f}")
    print(json.dumps({"scenario": args.scenario, "configuration": args.configuration,
                      "projections": len(calls), "python_us": 1e6 * best["python"],
                      "compiled_us": 1e6 * best["compiled"], "ratio": ratio}))


if __name__ == "__main__":
    main()
