"""A fleet on one road: N vehicles drive the same scenario one after another, and each one's own
friction estimates become shared reports for those behind it (issue 40, decision 0060).

Vehicle k (1-based) starts ``shared.fleet_delay_s`` after vehicle k − 1, with seed ``seed + k −
1`` (its own sensor noise). What vehicle j measured reaches vehicle k > j as a report: every
planning step at which j's slip-based estimator measured (``local_available``) becomes a
:class:`~mufusion.estimators.shared.FrictionReport` at j's position along s, with the local
estimator's declared error as its margin, the section's ``position_std_m`` as its position error,
stamped with j's time on k's clock (``t − (k − j) · delay``). The reports of all vehicles ahead
are then made wrong as the ``[shared]`` section says, sent over its link and fused by a shared
configuration; any other configuration ignores them (a baseline fleet). The estimators never see
the true μ: a report is a sensor output of the vehicle that made it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from mufusion.configurations import Configuration, make_estimator
from mufusion.estimators import LOCAL_MAX_ERROR, class_table
from mufusion.estimators.comm import ReportInbox
from mufusion.estimators.shared import FrictionReport
from mufusion.scenarios.runner import Scenario, run_scenario
from mufusion.scenarios.shared_section import make_inbox
from mufusion.sim.log import RunLog

MAX_FLEET = 50
"""Most vehicles in one fleet run."""


def reports_from_log(
    log: RunLog,
    *,
    sender: str,
    t_shift_s: float = 0.0,
    position_std_m: float = 1.0,
    margin: float = LOCAL_MAX_ERROR,
) -> list[FrictionReport]:
    """A vehicle's own local estimates as reports: one per planning step at which it measured.

    Parameters
    ----------
    log
        The vehicle's run log (its ``planning_steps``: ``t_s``, ``s_m``, ``local_available``,
        ``local_mu``).
    sender
        The vehicle's pseudonym.
    t_shift_s
        Added to the log's times: the vehicle's start on the common clock [s].
    position_std_m, margin
        Position error along s [m] and the local estimate's declared 95 % error [-].
    """
    steps = log.planning_steps
    if len(steps) == 0:
        return []
    measured = steps[steps["local_available"].astype(bool)]
    return [
        FrictionReport.numeric(
            float(s), float(np.clip(mu, 0.0, 2.0)), margin, t_created_s=float(t) + t_shift_s,
            position_std_m=position_std_m, sender=sender,
        )
        for t, s, mu in zip(measured["t_s"], measured["s_m"], measured["local_mu"], strict=True)
        if np.isfinite(mu)
    ]


def run_fleet(
    cfg: Scenario,
    configuration: Configuration | str,
    n_vehicles: int,
    *,
    on_vehicle: Callable[[int, RunLog, ReportInbox | None], None] | None = None,
) -> list[RunLog]:
    """Run ``n_vehicles`` vehicles one after another on ``cfg`` (module docstring).

    Parameters
    ----------
    cfg
        Validated scenario; its ``[shared]`` section sets the delay, the link and the wrong
        reports (its ``reports_file`` is not read: the reports come from the fleet).
    configuration
        Every vehicle's configuration (a shared one to use the reports).
    n_vehicles
        Number of vehicles, in [1, ``MAX_FLEET``].
    on_vehicle
        Called with (k, log, inbox) after vehicle k's run (1-based; inbox: what it received,
        None for a configuration without reports).

    Returns
    -------
    list of RunLog
        Vehicle 1's first.

    Raises
    ------
    ValueError
        If ``n_vehicles`` is out of range or ``configuration`` is not a built-in one.
    """
    if isinstance(n_vehicles, bool) or not isinstance(n_vehicles, int):
        raise ValueError(f"n_vehicles must be an integer, got {n_vehicles!r}")
    if not 1 <= n_vehicles <= MAX_FLEET:
        raise ValueError(f"n_vehicles must lie in [1, {MAX_FLEET}], got {n_vehicles}")
    name = Configuration.parse(configuration)
    section = cfg.shared
    delay = section.fleet_delay_s
    classes = class_table(cfg.estimation.class_table)
    shared_so_far: list[FrictionReport] = []  # on the common clock (vehicle 1 starts at 0)
    logs: list[RunLog] = []
    for k in range(n_vehicles):
        start = k * delay
        vehicle = cfg.model_copy(update={"seed": cfg.seed + k})
        inbox = None
        if name.shares_reports:
            here = [replace(r, t_created_s=r.t_created_s - start) for r in shared_so_far]
            rng = np.random.default_rng(np.random.SeedSequence(cfg.seed, spawn_key=(3, k)))
            inbox = make_inbox(here, section, rng)
        source = make_estimator(name, classes=classes,
                                length_scale_m=cfg.estimation.length_scale_m,
                                shared=section.settings(), inbox=inbox,
                                safe_beyond_camera=cfg.estimation.safe_beyond_camera)
        log = run_scenario(vehicle, source)
        logs.append(log)
        if on_vehicle is not None:
            on_vehicle(k + 1, log, inbox)
        shared_so_far += reports_from_log(
            log, sender=f"vehicle-{k + 1}", t_shift_s=start,
            position_std_m=section.position_std_m,
        )
    return logs
