"""Run a command in its own session and leave nothing behind.

Commands that start process trees (a campaign's pool workers, a local Ray instance with its
raylet, GCS and workers) run here in a new session. The test can then ask whether the command
left any process alive, and whatever it left is killed before the test ends, so no orphan keeps
the test run's output pipe open after pytest has finished.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path


def session_members(session_id: int) -> list[int]:
    """Process ids whose session is ``session_id`` (Linux ``/proc``)."""
    members = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            if os.getsid(int(entry.name)) == session_id:
                members.append(int(entry.name))
        except (ProcessLookupError, PermissionError):
            continue
    return members


def wait_until_session_empty(session_id: int, timeout_s: float) -> list[int]:
    """Poll until no process of the session is left (zombies count as gone); return the rest."""
    deadline = time.monotonic() + timeout_s
    while True:
        alive = [pid for pid in session_members(session_id) if not _is_zombie(pid)]
        if not alive or time.monotonic() > deadline:
            return alive
        time.sleep(0.1)


def command_lines(pids: Sequence[int]) -> list[str]:
    """Each process's command line (for a failing test's message: what was left alive)."""
    lines = []
    for pid in pids:
        try:
            raw = Path(f"/proc/{pid}/cmdline").read_bytes()
        except OSError:
            raw = b"(gone)"
        text = raw.replace(b"\0", b" ").decode(errors="replace").strip()
        lines.append(f"{pid}: {text}")
    return lines


def _is_zombie(pid: int) -> bool:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return True
    return stat.rsplit(")", 1)[1].split()[0] == "Z"


def mufusion_command(*args: str) -> list[str]:
    """``python -m mufusion ARGS`` with this interpreter."""
    return [sys.executable, "-m", "mufusion", *args]


def child_environment() -> dict[str, str]:
    """This environment, with this interpreter's import path, and Ray kept off the network."""
    return {
        **os.environ,
        "PYTHONPATH": os.pathsep.join(sys.path),
        "RAY_USAGE_STATS_ENABLED": "0",
    }


@contextmanager
def _sigint_not_ignored() -> Iterator[None]:
    """While active, SIGINT is caught (Python's KeyboardInterrupt) instead of ignored in this
    process, so a child started meanwhile gets its default disposition.

    A shell without job control starts a background command (``pytest ... &`` in a script) with
    SIGINT ignored, and an ignored signal stays ignored across ``exec``: the commands the tests
    send SIGINT to would then never see it (the campaign ran on to its end, measured). A caught
    signal is reset to its default by ``exec``. Only the main thread may set a handler.
    """
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGINT) is not signal.SIG_IGN):
        yield
        return
    signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextmanager
def isolated(cmd: Sequence[str], **popen_kwargs) -> Iterator[subprocess.Popen]:
    """Start ``cmd`` as the leader of a new session, with Ctrl-C's signal as a terminal gives it;
    on exit kill whatever of it is left."""
    with _sigint_not_ignored():
        proc = subprocess.Popen(list(cmd), start_new_session=True, env=child_environment(),
                                **popen_kwargs)
    try:
        yield proc
    finally:
        for pid in session_members(proc.pid):
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        proc.wait(timeout=30)
