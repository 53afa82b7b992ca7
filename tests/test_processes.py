"""The helper that starts the commands the tests signal (tests/processes.py)."""

from __future__ import annotations

import signal
import subprocess
import sys

from processes import isolated

SHOW_SIGINT = "import signal; print(signal.getsignal(signal.SIGINT) is signal.default_int_handler)"


def test_a_command_gets_sigint_as_from_a_terminal_though_the_suite_ignores_it():
    # As in a suite started in the background by a shell without job control.
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        with isolated([sys.executable, "-c", SHOW_SIGINT], stdout=subprocess.PIPE,
                      text=True) as proc:
            output, _ = proc.communicate(timeout=30)
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN  # the suite's own, restored
    finally:
        signal.signal(signal.SIGINT, previous)
    # Python installs KeyboardInterrupt's handler only where SIGINT starts at its default.
    assert output.strip() == "True"
