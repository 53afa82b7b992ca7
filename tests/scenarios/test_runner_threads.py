"""A scenario run limits the BLAS thread pools to one thread, and restores them afterwards."""

from __future__ import annotations

from threadpoolctl import threadpool_info, threadpool_limits

from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import run_scenario


def _blas_threads() -> list[int]:
    return [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]


def test_run_uses_one_blas_thread() -> None:
    seen: list[list[int]] = []

    def spy(t_s: float) -> None:  # called inside the run, after each planning step
        seen.append(_blas_threads())

    # The test session keeps one BLAS thread (root conftest.py): two pools here, so that the run's
    # limit to one and its restoring of the pools afterwards are both seen.
    with threadpool_limits(limits=2, user_api="blas"):
        before = _blas_threads()
        assert before and all(n == 2 for n in before)
        run_scenario(load_scenario("popup", ["duration_s=0.6"]), "GT", progress=spy)
        assert seen and seen[0] and all(n == 1 for n in seen[0])
        assert _blas_threads() == before
