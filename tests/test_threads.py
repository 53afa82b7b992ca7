"""One BLAS thread covers every OpenBLAS in the process, CasADi's bundled one included."""

from __future__ import annotations

from threadpoolctl import threadpool_info, threadpool_limits

from mufusion._threads import CASADI_OPENBLAS_PREFIX, load_casadi_ipopt, one_blas_thread


def _blas_threads() -> dict[str, int]:
    return {pool["filepath"]: pool["num_threads"] for pool in threadpool_info()
            if pool["user_api"] == "blas"}


def test_casadis_openblas_is_found_and_limited_and_restored(capfd) -> None:
    load_casadi_ipopt()
    load_casadi_ipopt()  # once per process: a second call loads nothing
    assert capfd.readouterr() == ("", "")  # and neither prints (no banner, no plug-in warning)
    # The test session runs one thread (conftest.py); two here, so that both the limit and its
    # undoing are seen.
    with threadpool_limits(limits=2, user_api="blas"):
        before = _blas_threads()
        casadi = [path for path in before if CASADI_OPENBLAS_PREFIX in path]
        assert casadi, f"CasADi's OpenBLAS not among the BLAS pools: {sorted(before)}"
        assert all(n == 2 for n in before.values())
        with one_blas_thread():
            inside = _blas_threads()
            assert inside.keys() == before.keys() and all(n == 1 for n in inside.values())
        assert _blas_threads() == before
