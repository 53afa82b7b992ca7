"""A scenario run limits the BLAS thread pools to one thread, and restores them afterwards."""

from __future__ import annotations

from threadpoolctl import threadpool_info

from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import run_scenario
from mufusion.sim.loop import ClosedLoop


def _blas_threads() -> list[int]:
    return [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]


def test_run_uses_one_blas_thread(monkeypatch) -> None:
    seen: list[list[int]] = []
    original = ClosedLoop._run

    def spy(self, *args, **kwargs):
        seen.append(_blas_threads())
        return original(self, *args, **kwargs)

    monkeypatch.setattr(ClosedLoop, "_run", spy)
    before = _blas_threads()
    run_scenario(load_scenario("popup", ["duration_s=0.6"]), "GT")
    assert seen and seen[0] and all(n == 1 for n in seen[0])
    assert _blas_threads() == before
