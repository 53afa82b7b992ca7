"""The acados template's CasADi-version notice is logged (``--verbose``), not printed; one
solver is built by one process at a time."""

from __future__ import annotations

import logging
import sys
import threading
from pathlib import Path

import pytest

from mufusion.planner import acados_loader
from mufusion.planner.acados_loader import AcadosUnavailable, build_lock, load_acados_template


def test_the_casadi_version_notice_is_not_printed_at_a_solver_build(capfd, caplog) -> None:
    try:
        template = load_acados_template()
    except AcadosUnavailable as err:
        pytest.skip(f"acados unavailable: {err}")
    for name in ("acados_ocp_solver", "acados_sim_solver"):  # where a build calls it
        module = sys.modules[f"{template.__name__}.{name}"]
        with caplog.at_level(logging.INFO, logger="mufusion.planner.acados_loader"):
            module.check_casadi_version()
    assert "officially supported" not in capfd.readouterr().out


def test_a_second_builder_waits_until_the_first_has_finished(tmp_path: Path) -> None:
    # flock conflicts between open file descriptions, so a thread stands in for the second
    # process (a parallel test worker or a campaign worker needing the same solver).
    export = tmp_path / "cache" / "tamp_0123456789abcdef"
    events: list[str] = []

    def second_builder() -> None:
        with build_lock(export):
            events.append("second builds or finds the solver")

    with build_lock(export):
        assert export.is_dir()
        second = threading.Thread(target=second_builder)
        second.start()
        second.join(timeout=0.5)
        assert second.is_alive()  # blocked while the first holds the lock
        events.append("first has built the solver")
    second.join(timeout=10.0)
    assert not second.is_alive()
    assert events == ["first has built the solver", "second builds or finds the solver"]


def test_a_solver_directory_that_cannot_be_made_is_named(tmp_path: Path) -> None:
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    with pytest.raises(AcadosUnavailable, match=r"cannot lock the solver directory .*a-file"):
        with build_lock(blocker / "tamp_0123456789abcdef"):
            pass


def test_a_read_only_solver_directory_is_used_without_the_lock(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # A cache built elsewhere and shared read-only: no lock file can be made, nothing is built.
    # (Tests may run as root, which writes anyway: the refusal is simulated.)
    export = tmp_path / "tamp_0123456789abcdef"
    export.mkdir()

    def refused(path, mode="r"):
        raise PermissionError(13, "Read-only file system", str(path))

    monkeypatch.setattr(acados_loader, "open", refused, raising=False)
    monkeypatch.setattr(acados_loader.os, "access", lambda path, mode: False)
    with build_lock(export):
        entered = True
    assert entered and not (export / ".build.lock").exists()
