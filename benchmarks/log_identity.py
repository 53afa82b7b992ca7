"""Whether a speed-up kept the runs: every logged value of 20 runs, recorded and compared exactly.

Run: ``python benchmarks/log_identity.py record FILE`` on the code before a change and again on
the code after it, then ``python benchmarks/log_identity.py compare BEFORE AFTER`` (exit 1 on
any difference). The runs: both paper scenarios (turn, pop-up) × the five configurations (GT, L,
P, F, F-safe) × the product's defaults and the paper's method
(``mufusion.reproduction.variants.PAPER_METHOD``). Every column of every table except the
wall-clock ``timing`` is compared with ``np.array_equal`` (NaN equal to NaN), and the solver
messages and the run's metadata as they are. The file is a pickle: read only your own.
"""

from __future__ import annotations

import argparse
import pickle
import sys
from pathlib import Path
from typing import Any

import numpy as np

from mufusion.reproduction.variants import PAPER_METHOD
from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import run_scenario
from mufusion.sim.log import TABLES

SCENARIOS = ("turn", "popup")
CONFIGURATIONS = ("GT", "L", "P", "F", "F-safe")
METHODS: dict[str, tuple[str, ...]] = {"product": (), "paper": PAPER_METHOD}
WALL_CLOCK_TABLES = ("timing",)


def record(path: Path) -> None:
    """Run the 20 runs and write what they logged to ``path``."""
    runs: dict[str, dict[str, Any]] = {}
    for scenario in SCENARIOS:
        for method, overrides in METHODS.items():
            cfg = load_scenario(scenario, list(overrides))
            for configuration in CONFIGURATIONS:
                log = run_scenario(cfg, configuration)
                logged: dict[str, Any] = {
                    table: {column: log.frame(table)[column].to_numpy()
                            for column in log.frame(table).columns}
                    for table in TABLES if table not in WALL_CLOCK_TABLES
                }
                logged["solver_messages"] = list(log.solver_messages)
                logged["meta"] = log.meta.model_dump_json()
                runs[f"{scenario}/{method}/{configuration}"] = logged
                print(f"{scenario} {method} {configuration}: {len(log.timeseries)} ticks",
                      flush=True)
    path.write_bytes(pickle.dumps(runs))


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    if a.dtype != b.dtype or a.shape != b.shape:
        return False
    return bool(np.array_equal(a, b, equal_nan=a.dtype.kind in "fc"))


def compare(before: Path, after: Path) -> list[str]:
    """The differences between two recordings (empty: every logged value equal)."""
    a, b = pickle.loads(before.read_bytes()), pickle.loads(after.read_bytes())
    if a.keys() != b.keys():
        return [f"different runs: {sorted(a.keys() ^ b.keys())}"]
    differences = []
    for run, logged in a.items():
        for part, value in logged.items():
            other = b[run].get(part)
            if not isinstance(value, dict):
                if value != other:
                    differences.append(f"{run}: {part}")
            elif other is None or value.keys() != other.keys():
                differences.append(f"{run}: {part} has other columns")
            else:
                differences += [f"{run}: {part}.{column}" for column in value
                                if not _same(np.asarray(value[column]),
                                             np.asarray(other[column]))]
    return differences


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("record", help="run the 20 runs, write their logs").add_argument(
        "file", type=Path)
    comparing = sub.add_parser("compare", help="compare two recordings exactly")
    comparing.add_argument("before", type=Path)
    comparing.add_argument("after", type=Path)
    args = parser.parse_args()
    if args.command == "record":
        record(args.file)
        return
    differences = compare(args.before, args.after)
    for difference in differences:
        print(difference)
    runs = len(pickle.loads(args.before.read_bytes()))
    print(f"{runs} runs, {len(differences)} differences")
    sys.exit(1 if differences else 0)


if __name__ == "__main__":
    main()
