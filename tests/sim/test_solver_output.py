"""Capturing what C code prints to file descriptor 1: everything caught, nothing leaks later."""

from __future__ import annotations

import ctypes

from mufusion.sim.solver_output import captured_output

_LIBC = ctypes.CDLL(None)


def test_c_printf_is_captured_even_unflushed_and_the_descriptor_restored(capfd) -> None:
    with captured_output() as lines:
        _LIBC.printf(b"\nSQP_RTI: QP solver returned error status 3 QP iteration 40.\n")
        _LIBC.printf(b"no newline yet")  # still in C's buffer when the block ends
    assert lines == ["SQP_RTI: QP solver returned error status 3 QP iteration 40.",
                     "no newline yet"]
    _LIBC.printf(b"after\n")
    _LIBC.fflush(None)
    assert capfd.readouterr().out == "after\n"  # restored, and nothing captured leaked out


def test_nothing_printed_gives_no_lines() -> None:
    with captured_output() as lines:
        pass
    assert lines == []


def test_a_capture_inside_another_leaves_the_lines_to_the_outer_one(capfd) -> None:
    with captured_output() as outer:
        with captured_output() as inner:
            _LIBC.printf(b"message\n")
        _LIBC.printf(b"later\n")
    assert inner == [] and outer == ["message", "later"]
    _LIBC.printf(b"after\n")
    _LIBC.fflush(None)
    assert capfd.readouterr().out == "after\n"
