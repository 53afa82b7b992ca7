"""How shared friction reports travel: rate, latency, packet loss, validity, message content.

Pure functions; every random draw comes from a seeded :class:`numpy.random.Generator` passed in.

**Link** (:class:`CommModel`): a sender broadcasts at most ``rate_hz`` reports per second (the
latest estimate at each slot), each message is lost with probability ``loss``, arrives after
``latency_s`` plus an exponential jitter of mean ``jitter_s`` (C-ITS trials: < 2 s end to end),
and the receiver drops it once older than ``validity_s`` (DENM's validityDuration, default
600 s).

**Content** (what the standards allow a message to carry; ``../shared/notes/shared-friction.md``),
each mapped to a :class:`~mufusion.estimators.shared.FrictionReport` by one rule
(:func:`decode`):

* ``"vss"`` (COVESA VSS ``Vehicle.ADAS.ESC.RoadFriction``): LowerBound (a *5 %* quantile),
  MostProbable and UpperBound in percent. The report's bounds are two-sided 95 % (2.5 %
  quantiles), wider by 1.96 / 1.645: ``lower = mp − (mp − LB) · 1.96 / 1.645``, likewise upper.
  Percent values are rounded outwards when encoded (lower down, upper up).
* ``"ivim"`` (ETSI IVIM road-surface container, frictionCoefficient 0–100 %, 101 unavailable): a
  numeric μ without uncertainty; the receiver declares one, ``IVIM_MARGIN`` plus the half step of
  the integer percent (0.005).
* ``"denm"`` (ETSI DENM cause 6, adverseWeatherCondition-Adhesion): a sub-cause (ice, snow,
  frost, …) and informationQuality 1–7, no μ. Each sub-cause maps to a μ interval
  (``DENM_ADHESION``); a lower quality widens it downwards (``lower·q/7 + μ_min·(1 − q/7)``). A
  DENM is a warning: it is only sent for μ below ``DENM_SEND_BELOW`` and, being low, can only
  lower μ̂ (the fusion's one-sided rule keeps low reports).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np

from mufusion.estimators.shared import FrictionReport, check_in

MessageKind = Literal["vss", "ivim", "denm"]
MESSAGE_KINDS: tuple[str, ...] = ("vss", "ivim", "denm")

Z95_TWO_SIDED = 1.96
"""2.5 % quantile of the standard normal, negated: the report's bounds."""
Z95_ONE_SIDED = 1.645
"""5 % quantile of the standard normal, negated: VSS's LowerBound."""

IVIM_MARGIN = 0.1
"""95 % half-width the receiver declares for an IVIM μ, which carries none [-] (the camera's wet
class margin: a roadside sensor is no better than a forward camera)."""

DENM_MU_MIN = 0.05
"""Lowest μ a DENM can stand for [-] (a widened interval never goes below it)."""

DENM_SEND_BELOW = 0.4
"""An adhesion DENM is sent only when the estimate is below this μ [-] (a warning, not a map)."""

DENM_ADHESION: dict[int, tuple[float, float]] = {
    1: (0.2, 0.5),   # heavyFrostOnRoad
    4: (0.15, 0.4),  # snowOnRoad
    5: (0.1, 0.25),  # iceOnRoad
    6: (0.05, 0.2),  # blackIceOnRoad
    7: (0.15, 0.45),  # oilOnRoad
    9: (0.05, 0.2),  # instantBlackIce
}
"""DENM adhesion sub-cause → μ interval [-] (ours: typical friction of each surface; the standard
defines no μ). A sub-cause not listed (0 unavailable, fuel, mud, chippings, salted) gives
``(DENM_MU_MIN, DENM_SEND_BELOW)``."""


@dataclass(frozen=True)
class CommModel:
    """The link between senders and the receiver.

    Attributes
    ----------
    rate_hz
        Most reports a sender broadcasts per second [Hz], in (0, 100].
    latency_s
        Fixed part of the delivery delay [s], in [0, 60].
    jitter_s
        Mean of the exponential extra delay [s], in [0, 60].
    loss
        Probability a message is lost [-], in [0, 1).
    validity_s
        The receiver drops a message older than this [s], in (0, 86 400] (DENM's maximum).
    message
        Message content, one of ``MESSAGE_KINDS``.
    """

    rate_hz: float = 5.0
    latency_s: float = 0.5
    jitter_s: float = 0.3
    loss: float = 0.1
    validity_s: float = 600.0
    message: MessageKind = "vss"

    def __post_init__(self) -> None:
        check_in("rate_hz", self.rate_hz, 1e-9, 100.0, " Hz")
        check_in("latency_s", self.latency_s, 0.0, 60.0, " s")
        check_in("jitter_s", self.jitter_s, 0.0, 60.0, " s")
        check_in("loss", self.loss, 0.0, 1.0 - 1e-12)
        check_in("validity_s", self.validity_s, 1e-9, 86400.0, " s")
        if self.message not in MESSAGE_KINDS:
            raise ValueError(f"message must be one of {MESSAGE_KINDS}, got {self.message!r}")


@dataclass(frozen=True)
class Delivery:
    """A report as the receiver gets it: decoded content and arrival time [s]."""

    report: FrictionReport
    t_arrival_s: float


def thin_to_rate(reports: Sequence[FrictionReport], rate_hz: float) -> list[FrictionReport]:
    """Per sender, the latest report in each slot of ``1 / rate_hz`` seconds (by creation time).

    Examples
    --------
    >>> rs = [FrictionReport.numeric(float(i), 0.5, 0.025, t_created_s=0.1 * i) for i in range(20)]
    >>> [round(r.t_created_s, 3) for r in thin_to_rate(rs, 1.0)]
    [0.9, 1.9]
    """
    slots: dict[tuple[str, int], FrictionReport] = {}
    for r in sorted(reports, key=lambda r: r.t_created_s):
        slots[(r.sender, math.floor(r.t_created_s * rate_hz))] = r
    return sorted(slots.values(), key=lambda r: r.t_created_s)


def transmit(
    reports: Sequence[FrictionReport], comm: CommModel, rng: np.random.Generator
) -> list[Delivery]:
    """Send ``reports`` over the link: thinned to the rate, encoded, lost, delayed, decoded.

    A DENM is only sent for a report below ``DENM_SEND_BELOW``. Draws: one uniform (loss) and one
    exponential (jitter) per sent message, in order of creation time.
    """
    out: list[Delivery] = []
    for r in thin_to_rate(reports, comm.rate_hz):
        msg = encode(r, comm.message)
        lost = rng.random() < comm.loss
        delay = comm.latency_s + (rng.exponential(comm.jitter_s) if comm.jitter_s > 0 else 0.0)
        if msg is None or lost:
            continue
        out.append(Delivery(decode(msg, r), r.t_created_s + delay))
    return out


def received(deliveries: Sequence[Delivery], t_s: float, comm: CommModel) -> list[FrictionReport]:
    """The reports that have arrived by ``t_s`` and are still valid (age ≤ ``validity_s``)."""
    return [
        d.report for d in deliveries
        if d.t_arrival_s <= t_s and t_s - d.report.t_created_s <= comm.validity_s
    ]


@dataclass(frozen=True)
class Message:
    """An encoded report: the kind and its fields as the standard carries them."""

    kind: str
    fields: tuple[int, ...]
    """VSS: (lower %, most probable %, upper %); IVIM: (μ %,); DENM: (sub-cause, quality)."""


def _denm_subcause(mu: float) -> int:
    """The sub-cause whose interval holds ``mu`` best (its centre nearest), 0 if none does."""
    best, dist = 0, math.inf
    for code, (lo, hi) in DENM_ADHESION.items():
        if lo <= mu <= hi and abs(mu - 0.5 * (lo + hi)) < dist:
            best, dist = code, abs(mu - 0.5 * (lo + hi))
    return best


def _denm_quality(margin: float) -> int:
    """informationQuality 1–7 from a 95 % half-width: 7 at ≤ 0.025, one step per 0.025 more."""
    return int(max(1, min(7, 7 - math.ceil(max(margin - 0.025, 0.0) / 0.025 - 1e-9))))


def encode(report: FrictionReport, kind: str) -> Message | None:
    """The message ``kind`` carrying ``report`` (None: a DENM is not sent for this μ)."""
    if kind == "vss":
        scale = Z95_ONE_SIDED / Z95_TWO_SIDED  # a 2.5 % quantile moved to the 5 % quantile
        lb = report.mu - (report.mu - report.lower_mu) * scale
        ub = report.mu + (report.upper_mu - report.mu) * scale
        return Message(kind, (math.floor(100 * lb), round(100 * report.mu), math.ceil(100 * ub)))
    if kind == "ivim":
        return Message(kind, (int(min(100, max(0, round(100 * report.mu)))),))
    if kind == "denm":
        if report.mu >= DENM_SEND_BELOW:
            return None
        return Message(kind, (_denm_subcause(report.mu), _denm_quality(report.margin)))
    raise ValueError(f"message kind must be one of {MESSAGE_KINDS}, got {kind!r}")


def decode(msg: Message, header: FrictionReport) -> FrictionReport:
    """The fusion input a message stands for (module docstring); position, time and sender come
    from ``header`` (the message's own header fields)."""
    if msg.kind == "vss":
        lb, mp, ub = (v / 100.0 for v in msg.fields)
        widen = Z95_TWO_SIDED / Z95_ONE_SIDED
        lower = max(0.0, mp - (mp - lb) * widen)
        upper = min(2.0, mp + (ub - mp) * widen)
        return replace(header, mu=mp, lower_mu=min(lower, mp), upper_mu=max(upper, mp))
    if msg.kind == "ivim":
        mu = msg.fields[0] / 100.0
        margin = IVIM_MARGIN + 0.005
        return replace(header, mu=mu, lower_mu=max(0.0, mu - margin), upper_mu=mu + margin)
    if msg.kind == "denm":
        code, quality = msg.fields
        lo, hi = DENM_ADHESION.get(code, (DENM_MU_MIN, DENM_SEND_BELOW))
        q = max(1, min(7, quality)) / 7.0  # 0 (unavailable) counts as the lowest
        lower = lo * q + DENM_MU_MIN * (1.0 - q)
        return replace(header, mu=0.5 * (lower + hi), lower_mu=lower, upper_mu=hi)
    raise ValueError(f"message kind must be one of {MESSAGE_KINDS}, got {msg.kind!r}")


@dataclass(frozen=True)
class ReportInbox:
    """What one receiver gets over a link: the deliveries, read by time (pure; no state).

    Examples
    --------
    >>> r = FrictionReport.numeric(5.0, 0.5, 0.025, t_created_s=0.0)
    >>> box = ReportInbox((Delivery(r, 1.0),), CommModel(validity_s=60.0))
    >>> len(box.at(0.5)), len(box.at(2.0)), len(box.at(100.0))
    (0, 1, 0)
    """

    deliveries: tuple[Delivery, ...]
    comm: CommModel

    def at(self, t_s: float) -> list[FrictionReport]:
        """The reports arrived by ``t_s`` and still valid (:func:`received`)."""
        return received(self.deliveries, t_s, self.comm)
