"""Test-collection settings shared by tests/ and the doctests in src/."""

from __future__ import annotations

from typing import Any

import pytest
from hypothesis import settings

# Every property test draws the same examples on every run and on every machine: a failure is
# found again where it was found, in CI as at a desk, never by the luck of a run (the project
# draws nothing unseeded). Tests that set their own settings keep this unless they say otherwise.
settings.register_profile("deterministic", derandomize=True, database=None)
settings.load_profile("deterministic")

# ``python -m mufusion`` runs the CLI when imported: not a module for doctests.
collect_ignore = ["src/mufusion/__main__.py"]

# The files that take longest (docs/performance.md, "Tests"), longest first: the whole
# reproduction (which, on an empty solver cache, also builds the eight solvers of the paper's
# settings and the authors'), the campaign engines (local Ray instances, bounded waits) and GT's
# closed loops over the general grids.
LONGEST_FIRST = (
    "tests/test_reproduction.py",
    "tests/campaign/test_campaign_engines.py",
    "tests/scenarios/test_general_grids.py",
)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Order the tests: the longest files first, then the tests marked ``slow``, then the rest,
    each in the collection's order.

    With parallel workers (README's ``-n auto``; pyproject hands out whole files, in this order)
    the long files start at once and the short ones fill the workers' ends, instead of a long
    file starting last and running alone while the other worker idles.
    """

    def rank(item: pytest.Item) -> tuple[int, bool]:
        path = item.nodeid.partition("::")[0]
        first = LONGEST_FIRST.index(path) if path in LONGEST_FIRST else len(LONGEST_FIRST)
        return first, item.get_closest_marker("slow") is None

    items.sort(key=rank)


# One BLAS thread per test process, as a scenario run and a campaign worker have (runner.py,
# engines.py). OpenBLAS otherwise starts one thread per core in every process; with a worker per
# core (``-n auto``) the threads of one wait, spinning, for cores the other worker holds. The
# property tests that call the fusion directly took 70 s of CPU that way, 4 s with one thread each
# (tests/fusion/test_shared_fusion.py and test_sender_cap.py, beside another job's two processes).
# CasADi's own OpenBLAS (IPOPT's linear solver; mufusion._threads) is loaded first so that the
# limit covers it too: the reference solves then give the same answer on any machine's core count
# (docs/decisions/0116).
# The limit holds for the whole session (the object is kept); tests/scenarios/test_runner_threads.py
# raises it again around the run whose limit it checks.
_BLAS_LIMIT: list[Any] = []


def pytest_configure(config: pytest.Config) -> None:
    """Limit the BLAS pools where tests run: here, or in pytest-xdist's workers (not in the
    controller that hands the tests out, which need not import NumPy for it)."""
    if getattr(config.option, "tx", None) and not hasattr(config, "workerinput"):
        return
    import numpy  # noqa: F401  (loads NumPy's OpenBLAS, and SciPy's, before the limit)
    import scipy.linalg  # noqa: F401

    from mufusion._threads import load_casadi_ipopt, one_blas_thread

    load_casadi_ipopt()
    _BLAS_LIMIT.append(one_blas_thread())
