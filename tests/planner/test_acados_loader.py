"""The acados template's CasADi-version notice is logged (``--verbose``), not printed."""

from __future__ import annotations

import logging
import sys

import pytest

from mufusion.planner.acados_loader import AcadosUnavailable, load_acados_template


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
