"""Shared friction reports (V2V / V2I): what another vehicle or a roadside unit reported.

A :class:`FrictionReport` is a sensor output of *another* vehicle (its slip-based estimate, its
fused lower bound) or of a roadside unit, received over a network: a position along the road,
a friction triple (lower / most probable / upper, 95 %), when it was created and by whom. The
receiving vehicle never sees the true μ through it, only what the sender estimated then.

How a report's uncertainty grows with its age and its position error is set by
:class:`SharedSettings` and applied by the fusion (:mod:`mufusion.fusion.reports`); how reports
travel (rate, latency, loss, validity, message content) is :mod:`mufusion.estimators.comm`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, get_args

REPORT_MU_RANGE = (0.0, 2.0)
"""Allowed μ of a report [-] (the fusion's ``MU_RANGE``)."""
ReportBound = Literal["consistent", "lowest"]
"""How safe mode's hard bound combines reports (:class:`SharedSettings`.report_bound)."""
REPORT_BOUNDS: tuple[str, ...] = get_args(ReportBound)
AgeKernel = Literal["matern32", "matern12"]
"""The time kernel a report ages with (:class:`SharedSettings`.age_kernel)."""
AGE_KERNELS: tuple[str, ...] = get_args(AgeKernel)


def check_in(name: str, value: object, lo: float, hi: float, unit: str = "") -> float:
    """``float(value)`` if it is a number within ``[lo, hi]``, else ValueError naming ``name``
    and the range (the one range check of the estimators' and the fusion's records)."""
    try:
        x = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite number, got {value!r}") from None
    if not lo <= x <= hi:  # also rejects NaN
        raise ValueError(f"{name} must lie in [{lo:g}, {hi:g}]{unit}, got {value!r}")
    return x


@dataclass(frozen=True)
class FrictionReport:
    """One friction report received from another vehicle or a roadside unit.

    Attributes
    ----------
    s_m
        Position along the road's reference path where the sender measured [m] (absolute, the
        map's s, not relative to the receiver), within ± 1e6 m.
    mu
        Most probable μ [-], in ``REPORT_MU_RANGE``.
    lower_mu, upper_mu
        The sender's 95 % bounds on μ at creation [-], ``lower_mu ≤ mu ≤ upper_mu``, in
        ``REPORT_MU_RANGE`` (a numeric report with a margin m has ``mu ∓ m``).
    t_created_s
        When the sender measured, on the receiver's clock [s] (finite).
    position_std_m
        Standard deviation of the position error along s [m], in [0, 100].
    sender
        The sender's identity as the network shows it (a pseudonym; many identities may belong
        to one sender, which the fusion cannot tell apart).

    Raises
    ------
    ValueError
        If a field is outside its range or the triple is not ordered (the message names it).

    Examples
    --------
    >>> round(FrictionReport(12.0, 0.5, 0.475, 0.525, t_created_s=3.0).margin, 6)
    0.025
    """

    s_m: float
    mu: float
    lower_mu: float
    upper_mu: float
    t_created_s: float = 0.0
    position_std_m: float = 0.0
    sender: str = "anonymous"

    def __post_init__(self) -> None:
        check_in("s_m", self.s_m, -1e6, 1e6, " m")
        for name in ("lower_mu", "mu", "upper_mu"):
            check_in(name, getattr(self, name), *REPORT_MU_RANGE)
        if not self.lower_mu <= self.mu <= self.upper_mu:
            raise ValueError(
                f"a report needs lower_mu <= mu <= upper_mu, got {self.lower_mu!r}, "
                f"{self.mu!r}, {self.upper_mu!r}"
            )
        if not math.isfinite(float(self.t_created_s)):
            raise ValueError(f"t_created_s must be finite, got {self.t_created_s!r}")
        check_in("position_std_m", self.position_std_m, 0.0, 100.0, " m")

    @classmethod
    def numeric(
        cls, s_m: float, mu: float, margin: float, **kwargs: object
    ) -> FrictionReport:
        """A report of ``mu ± margin`` (95 %), the bounds clipped into ``REPORT_MU_RANGE``."""
        check_in("margin", margin, 0.0, 1.0)
        lo, hi = REPORT_MU_RANGE
        return cls(s_m, mu, max(lo, mu - margin), min(hi, mu + margin), **kwargs)  # type: ignore[arg-type]

    @property
    def margin(self) -> float:
        """Symmetric 95 % half-width that covers both bounds [-]: the larger side."""
        return max(self.mu - self.lower_mu, self.upper_mu - self.mu)


@dataclass(frozen=True)
class SharedSettings:
    """How the fusion treats shared reports (decision 0060).

    Attributes
    ----------
    tau_s
        Ageing time constant τ [s], in [1, 1e6]: after τ a report has lost 63 % of what it told
        beyond the prior (the only published staleness horizon for slippery-road classes is
        0–120 min; 30 min sits in its middle).
    age_kernel
        The time kernel of the ageing (decision 0063): ``"matern32"``, μ changes at a finite
        rate (weather wets, dries and freezes a surface over minutes), so a few seconds' age
        costs almost nothing; ``"matern12"``, the rougher Ornstein–Uhlenbeck process of decision
        0060, whose variance grows in proportion to the age from the first second.
    validity_s
        Reports older than this are dropped [s], in (0, 1e6] (DENM's validityDuration).
    gradient_bound_per_m
        Declared bound G on |dμ/ds| within one camera class segment [1/m], in [0, 1].
    reach_m
        A report informs the hard bound at evaluation points within this distance of it (plus
        its 95 % position error) [m], in [0, 100].
    sender_cap
        Most reports of one sender counted within a length scale [-], in [1, 1e6].
    trust_test
        Whether reports optimistic beyond the combined bounds of the vehicle's own estimate are
        rejected (:func:`screen_reports`).
    report_bound
        How safe mode's hard bound combines the reports near an evaluation point (decision
        0063): ``"consistent"``, the highest lower bound among the reports that agree with the
        lowest upper bound there (a report wholly above another one's interval is left out);
        ``"lowest"``, the lowest lower bound (decision 0060; safe against any optimistic report
        as long as one honest report is near, but it takes every honest report at its worst).
    corroboration
        With ``"consistent"``: how many senders must vouch for a bound (the k-th highest of the
        senders' best bounds counts), in [1, 100]. 1 by default; 2 keeps one miscalibrated
        sender with a small offset from lifting the bound alone, but then a vehicle with one
        sender ahead gains nothing (decision 0063 measures both).
    """

    tau_s: float = 1800.0
    age_kernel: AgeKernel = "matern32"
    validity_s: float = 3600.0
    gradient_bound_per_m: float = 0.01
    reach_m: float = 2.0
    sender_cap: float = 3.0
    trust_test: bool = True
    report_bound: ReportBound = "consistent"
    corroboration: int = 1

    def __post_init__(self) -> None:
        check_in("tau_s", self.tau_s, 1.0, 1e6, " s")
        check_in("validity_s", self.validity_s, 1e-9, 1e6, " s")
        check_in("gradient_bound_per_m", self.gradient_bound_per_m, 0.0, 1.0, " 1/m")
        check_in("reach_m", self.reach_m, 0.0, 100.0, " m")
        check_in("sender_cap", self.sender_cap, 1.0, 1e6)
        if not isinstance(self.trust_test, bool):
            raise ValueError(f"trust_test must be a bool, got {self.trust_test!r}")
        if isinstance(self.corroboration, bool) or not isinstance(self.corroboration, int):
            raise ValueError(f"corroboration must be an integer, got {self.corroboration!r}")
        check_in("corroboration", self.corroboration, 1, 100)
        if self.age_kernel not in AGE_KERNELS:
            raise ValueError(
                f"age_kernel must be one of {list(AGE_KERNELS)}, got {self.age_kernel!r}"
            )
        if self.report_bound not in REPORT_BOUNDS:
            raise ValueError(
                f"report_bound must be one of {list(REPORT_BOUNDS)}, got {self.report_bound!r}"
            )


DEFAULT_SHARED = SharedSettings()
"""The default report handling (τ = 1800 s, G = 0.01 /m, reach 2 m, 3 reports per sender)."""
