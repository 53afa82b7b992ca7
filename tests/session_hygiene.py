"""Session hygiene: the test run ends with no child process and no foreign thread left.

A pytest plugin, loaded by ``-p session_hygiene`` in pyproject.toml (a root ``conftest.py``
would share its module name with the per-directory ones under ``--doctest-modules``).

Campaign tests fork worker pools in this process. A worker or thread that outlived its test would
keep the interpreter from exiting (``concurrent.futures`` and ``multiprocessing`` join them at
exit) after every test has passed. At the end of the session any such leftover is named in the
terminal summary and stopped, so the run always ends. With parallel workers (``-n``) each worker
checks its own process at its end and reports to the controller, which names them.
"""

from __future__ import annotations

import multiprocessing
import threading

import pytest

_LEFTOVERS: list[str] = []


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    for child in multiprocessing.active_children():
        _LEFTOVERS.append(f"child process {child.name} (pid {child.pid})")
        child.terminate()
        child.join(timeout=10.0)
    for thread in threading.enumerate():
        if thread is not threading.main_thread() and not thread.daemon and thread.is_alive():
            _LEFTOVERS.append(f"non-daemon thread {thread.name}")
    workeroutput = getattr(session.config, "workeroutput", None)  # set in an xdist worker only
    if workeroutput is not None:
        workeroutput["leftovers"] = list(_LEFTOVERS)


@pytest.hookimpl(optionalhook=True)  # pytest-xdist's hook: in the controller, as a worker ends
def pytest_testnodedown(node, error) -> None:
    worker = node.gateway.id
    for line in getattr(node, "workeroutput", {}).get("leftovers", []):
        _LEFTOVERS.append(f"{line} in worker {worker}")


def pytest_terminal_summary(terminalreporter) -> None:
    if _LEFTOVERS:
        terminalreporter.write_sep("=", "left behind by the tests (stopped at the end)")
        for line in _LEFTOVERS:
            terminalreporter.write_line(line)
