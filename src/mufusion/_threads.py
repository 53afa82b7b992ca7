"""One BLAS thread where mufusion computes: every OpenBLAS in the process, CasADi's own included.

A closed-loop run, a campaign worker and the transient oracle each compute on one core. OpenBLAS
otherwise starts a thread per core in every process, and beside other workers those threads spin
for cores that are busy; worse, the number of threads changes the order of a sum, so IPOPT's
answers depended on the machine's core count (the oracle's least-time turn in
``tests/scenarios/test_feasibility_transient.py``: 3.53 s with two threads, a 3.85 s local
optimum with one; docs/decisions/0116).

NumPy's and SciPy's OpenBLAS are found by ``threadpoolctl`` as they are. CasADi's wheel brings a
third, ``libcasadi-tp-openblas``, which IPOPT's linear solver (MUMPS) calls and which
``threadpoolctl`` does not know by that file name: importing this module registers it, with the
same OpenBLAS controller (the library exports OpenBLAS' thread API unchanged). CasADi loads it
with its IPOPT plug-in, so a limit covers it only once a solver has been created (or
:func:`load_casadi_ipopt` has run).
"""

from __future__ import annotations

import functools
from contextlib import AbstractContextManager

from threadpoolctl import OpenBLASController, ThreadpoolController, register

CASADI_OPENBLAS_PREFIX = "libcasadi-tp-openblas"


class _CasadiOpenBLASController(OpenBLASController):
    """CasADi's bundled OpenBLAS (the same library and symbols under another file name)."""

    filename_prefixes = (CASADI_OPENBLAS_PREFIX,)


register(_CasadiOpenBLASController)


def one_blas_thread() -> AbstractContextManager[object]:
    """Limit every BLAS library loaded in the process to one thread, at once.

    The loaded libraries are scanned on each call (about 2 ms), so a library loaded since the
    last call (CasADi's, when a reference solver was built) is covered too. Used as a context,
    each library returns to its thread count on leaving; called alone, the limit stays.
    """
    return ThreadpoolController().limit(limits=1, user_api="blas")


@functools.cache
def load_casadi_ipopt() -> None:
    """Load CasADi's IPOPT plug-in, and with it CasADi's OpenBLAS, so that a limit entered now
    covers the solves that follow (once per process)."""
    import casadi as ca  # the reference backend's dependency; imported where it is used

    # A solver is built rather than ``casadi.load_nlpsol`` called: the latter warns on stderr
    # when the plug-in is loaded already, and building one loads it quietly either way.
    x = ca.SX.sym("x")
    ca.nlpsol("load_ipopt", "ipopt", {"x": x, "f": x * x},
              {"print_time": False, "ipopt": {"print_level": 0, "sb": "yes"}})
