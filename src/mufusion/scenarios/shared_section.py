"""The scenario file's ``[shared]`` section: shared friction reports (decision 0060).

Read by the configurations F+shared and F-safe+shared (ignored by the others): where the reports
come from (a reports file, or the vehicles ahead in a fleet run), how the fusion treats them
(:class:`~mufusion.estimators.shared.SharedSettings`), how they travel
(:class:`~mufusion.estimators.comm.CommModel`) and which of them are wrong
(:class:`~mufusion.estimators.misbehaviour.WrongReports`). Each field's range is the record's;
a bad value is reported at load time naming the field.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Literal

import numpy as np
from pydantic import model_validator

from mufusion.estimators.comm import CommModel, ReportInbox, transmit
from mufusion.estimators.misbehaviour import WrongReports, corrupt
from mufusion.estimators.shared import (
    DEFAULT_SHARED,
    AgeKernel,
    FrictionReport,
    ReportBound,
    SharedSettings,
)
from mufusion.scenarios.sections import _Strict

_S, _C, _W = DEFAULT_SHARED, CommModel(), WrongReports()


class SharedSection(_Strict):
    """``[shared]``: see the module docstring; defaults give honest reports over a VSS link."""

    reports_file: str | None = None
    """A JSON list of reports (the fields of ``FrictionReport``; the map's s and times on this
    run's clock), relative to the working directory; None: no reports unless a fleet run
    supplies them."""
    # Defaults are the records' own (each number defined once).
    tau_s: float = _S.tau_s
    age_kernel: AgeKernel = _S.age_kernel
    validity_s: float = _S.validity_s
    gradient_bound_per_m: float = _S.gradient_bound_per_m
    reach_m: float = _S.reach_m
    sender_cap: float = _S.sender_cap
    trust_test: bool = _S.trust_test
    report_bound: ReportBound = _S.report_bound
    corroboration: int = _S.corroboration
    rate_hz: float = _C.rate_hz
    latency_s: float = _C.latency_s
    jitter_s: float = _C.jitter_s
    loss: float = _C.loss
    message: Literal["vss", "ivim", "denm"] = _C.message
    offset_share: float = _W.offset_share
    offset: float = _W.offset
    replay_share: float = _W.replay_share
    replay_age_s: float = _W.replay_age_s
    replay_drop: float = _W.replay_drop
    replay_restamped: bool = _W.replay_restamped
    sybil_share: float = _W.sybil_share
    sybil_identities: int = _W.sybil_identities
    fleet_delay_s: float = 10.0
    """Fleet runs: time between two vehicles' starts [s], in [0, 1e5]."""
    position_std_m: float = 0.5
    """Fleet runs: position error along s of a vehicle's reports [m] (the slip estimate stands
    for the tyres' contact patches, a wheelbase apart, and the map match has its own error)."""

    @model_validator(mode="after")
    def _records_accept(self) -> SharedSection:
        # The records check their own ranges and name the field: build each once here.
        self.settings()
        self.comm()
        self.wrong()
        if not 0.0 <= self.fleet_delay_s <= 1e5:
            raise ValueError(f"fleet_delay_s must lie in [0, 100000] s, got {self.fleet_delay_s}")
        if not 0.0 <= self.position_std_m <= 100.0:
            raise ValueError(f"position_std_m must lie in [0, 100] m, got {self.position_std_m}")
        return self

    def settings(self) -> SharedSettings:
        """How the fusion treats the reports."""
        return SharedSettings(
            tau_s=self.tau_s, age_kernel=self.age_kernel, validity_s=self.validity_s,
            gradient_bound_per_m=self.gradient_bound_per_m, reach_m=self.reach_m,
            sender_cap=self.sender_cap, trust_test=self.trust_test,
            report_bound=self.report_bound, corroboration=self.corroboration,
        )

    def comm(self) -> CommModel:
        """The link (its validity is the fusion's)."""
        return CommModel(
            rate_hz=self.rate_hz, latency_s=self.latency_s, jitter_s=self.jitter_s,
            loss=self.loss, validity_s=min(self.validity_s, 86400.0), message=self.message,
        )

    def wrong(self) -> WrongReports:
        """Which reports are wrong."""
        return WrongReports(
            offset_share=self.offset_share, offset=self.offset, replay_share=self.replay_share,
            replay_age_s=self.replay_age_s, replay_drop=self.replay_drop,
            replay_restamped=self.replay_restamped, sybil_share=self.sybil_share,
            sybil_identities=self.sybil_identities,
        )


def load_reports(path: str | Path) -> list[FrictionReport]:
    """The reports of a JSON file: a list of objects with ``FrictionReport``'s fields.

    Raises
    ------
    ValueError
        If the file cannot be read or parsed, or an entry is not a valid report (the message
        names the file and the entry's index).
    """
    try:
        entries = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise ValueError(f"shared.reports_file {str(path)!r}: {exc}") from None
    if not isinstance(entries, list):
        raise ValueError(f"shared.reports_file {str(path)!r} must hold a JSON list of reports")
    out = []
    for i, entry in enumerate(entries):
        try:
            out.append(FrictionReport(**entry))
        except (TypeError, ValueError) as exc:
            raise ValueError(f"shared.reports_file {str(path)!r}, report {i}: {exc}") from None
    return out


def make_inbox(
    reports: Sequence[FrictionReport], section: SharedSection, rng: np.random.Generator
) -> ReportInbox:
    """What a receiver gets of ``reports``: the wrong ones mixed in, then sent over the link."""
    sent = corrupt(reports, section.wrong(), rng)
    comm = section.comm()
    return ReportInbox(tuple(transmit(sent, comm, rng)), comm)


def scenario_inbox(section: SharedSection, seed: int) -> ReportInbox | None:
    """The inbox of a scenario's ``reports_file`` (None without one); draws from its own
    stream of ``seed``, so the sensors' draws do not depend on it."""
    if section.reports_file is None:
        return None
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(2,)))
    return make_inbox(load_reports(section.reports_file), section, rng)
