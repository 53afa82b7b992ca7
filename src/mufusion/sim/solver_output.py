"""What the solver library prints from C, kept off the terminal and in the run log.

acados reports a QP that stopped early (``SQP_RTI: QP solver returned error status 3 QP iteration
40.``) with ``printf``, straight to file descriptor 1: Python's ``sys.stdout`` never sees it, and
a ``reproduce`` printed 87 such lines between its progress bars. :func:`captured_output` points
descriptor 1 at a temporary file for the length of a run and hands back the lines; the runner
stores them in the run log (``solver_messages.txt``) and the metrics count them. It is done once
around a run, not around each solve: the planner's step pays nothing for it
(docs/performance-tests.md, "Quiet output").
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import sys
import tempfile
import threading
from collections.abc import Iterator

_LIBC = ctypes.CDLL(None)
# Descriptors a capture holds now. Restoring is only right last-in-first-out: a second capture of
# the same descriptor while one is active (another thread's run) captures nothing instead.
_HELD: set[int] = set()
_HELD_LOCK = threading.Lock()


def _flush_all() -> None:
    # Python's buffer, then C's: printf into a file or pipe is buffered in the C library, and
    # what is still there when descriptor 1 is restored would reach the terminal after all.
    for stream in (sys.stdout, sys.__stdout__):
        with contextlib.suppress(Exception):
            if stream is not None:
                stream.flush()
    _LIBC.fflush(None)


@contextlib.contextmanager
def captured_output(fd: int = 1) -> Iterator[list[str]]:
    """Send everything written to file descriptor ``fd`` into a temporary file while active.

    Yields a list that, once the block ends, holds the non-blank lines written meanwhile (C
    ``printf`` and Python ``print`` alike), undecodable bytes replaced. Where ``fd`` cannot be
    duplicated (closed), or another capture of it is active (in this or another thread; it gets
    the lines), nothing is captured and the list stays empty.

    Examples
    --------
    >>> with captured_output() as lines:
    ...     _ = os.write(1, b"\\nSQP_RTI: QP solver returned error status 3 QP iteration 7.\\n")
    >>> lines
    ['SQP_RTI: QP solver returned error status 3 QP iteration 7.']
    """
    lines: list[str] = []
    with _HELD_LOCK:
        held = fd in _HELD
        _HELD.add(fd)
    if held:
        yield lines
        return
    try:
        yield from _redirected(fd, lines)
    finally:
        with _HELD_LOCK:
            _HELD.discard(fd)


def _redirected(fd: int, lines: list[str]) -> Iterator[list[str]]:
    _flush_all()
    try:
        saved = os.dup(fd)
    except OSError:
        yield lines
        return
    try:
        with tempfile.TemporaryFile() as sink:
            os.dup2(sink.fileno(), fd)
            try:
                yield lines
            finally:
                _flush_all()
                os.dup2(saved, fd)
                sink.seek(0)
                text = sink.read().decode("utf-8", errors="replace")
                lines.extend(line for line in text.splitlines() if line.strip())
    finally:
        os.close(saved)
