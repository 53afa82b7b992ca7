"""The interface between the planner and an OCP solver."""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Protocol

import numpy as np

if TYPE_CHECKING:
    from mufusion.planner.config import PlannerConfig
    from mufusion.vehicle.params import VehicleParams

_log = logging.getLogger(__name__)


class PlannerBackend(Protocol):
    """What the planner needs from an OCP solver (acados RTI, CasADi reference, or a test double).

    ``solve`` takes the current state, the initial guess ``(N+1, 6)`` / ``(N, 3)``, the stage
    parameters ``(N, N_PARAMS)``, the tracking reference ``(N+1, 9)`` and its weights ``(9,)``,
    the corridor ``(N,)`` × 2, the lowest speed, the drive-force cap and the front braking's
    bound per stage ``(N,)`` (``inf``: the actuator's) and the soft speed ceiling of stages
    1 … N ``(N,)`` (``None``: none); it returns
    ``(status, states, inputs)`` with status 0 or 2 for a usable solution. It may raise.
    ``reset`` forgets every iterate and solver memory (after a failure).
    ``last_solve_retried`` is True when the latest solve needed a second, more robust attempt
    (logged with the plan).
    """

    last_solve_retried: bool

    def solve(
        self,
        x0: np.ndarray,
        guess_x: np.ndarray,
        guess_u: np.ndarray,
        p: np.ndarray,
        yref: np.ndarray,
        weights: np.ndarray,
        d_lo: np.ndarray,
        d_hi: np.ndarray,
        min_speed_mps: float,
        max_drive_force_n: float | np.ndarray | None = None,
        max_front_brake_force_n: np.ndarray | None = None,
        max_speed_mps: np.ndarray | None = None,
    ) -> tuple[int, np.ndarray, np.ndarray]: ...

    def reset(self) -> None: ...


def default_backend(params: VehicleParams, config: PlannerConfig) -> PlannerBackend:
    """acados RTI for ``config.backend == "acados"`` (CasADi + IPOPT where acados cannot be
    built or loaded, with a warning), else CasADi + IPOPT."""
    if config.backend == "acados":
        try:
            from mufusion.planner.acados_backend import AcadosBackend

            return AcadosBackend(params, config)
        except Exception as exc:  # any build/load failure → reference backend
            _log.warning("acados unavailable (%s); falling back to the CasADi backend", exc)
    from mufusion.planner.casadi_backend import CasadiBackend

    return CasadiBackend(params, config)
