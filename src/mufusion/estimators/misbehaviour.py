"""Wrong shared reports, for tests and studies: optimistic offsets, replays, Sybil identities.

The misbehaviour cases of V2X security research (F2MD) that matter to a friction map, applied to
the honest reports of a fleet before they are sent (pure; draws from a generator passed in):

* **Constant offset**: a share of the senders report μ higher by ``offset`` (a miscalibrated or
  malicious estimator), keeping their own margins.
* **Replay**: a share of the reports is re-sent from a time when the road was grippier by
  ``replay_drop`` (rain or frost since): the μ of then, stamped ``replay_age_s`` old, or stamped
  fresh when ``replay_restamped`` (the harmful kind: the age model cannot see it).
* **Sybil**: one attacker copies a share of the reports ``sybil_identities`` times, each copy
  offset by ``offset`` and under its own pseudonym, so that a per-sender cap counts each copy as
  a separate sender.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from mufusion.estimators.shared import REPORT_MU_RANGE, FrictionReport, check_in


@dataclass(frozen=True)
class WrongReports:
    """Shares and sizes of wrong reports (module docstring); all zero: every report honest.

    Attributes
    ----------
    offset_share
        Share of the senders with a constant optimistic offset [-], in [0, 1].
    offset
        The optimistic offset of offset senders and Sybil copies [-], in [0, 1].
    replay_share
        Share of the reports replaced by a replay [-], in [0, 1].
    replay_age_s
        How old a replayed report is [s], in [0, 1e6].
    replay_drop
        How much grippier the road was when the replayed report was made [-], in [0, 1].
    replay_restamped
        Whether a replay carries a fresh time stamp (else its true, old one).
    sybil_share
        Share of the reports the Sybil attacker copies [-], in [0, 1].
    sybil_identities
        Copies (pseudonyms) per copied report, in [1, 1000].
    """

    offset_share: float = 0.0
    offset: float = 0.2
    replay_share: float = 0.0
    replay_age_s: float = 3600.0
    replay_drop: float = 0.3
    replay_restamped: bool = True
    sybil_share: float = 0.0
    sybil_identities: int = 10

    def __post_init__(self) -> None:
        for name in ("offset_share", "offset", "replay_share", "replay_drop", "sybil_share"):
            check_in(name, getattr(self, name), 0.0, 1.0)
        check_in("replay_age_s", self.replay_age_s, 0.0, 1e6, " s")
        if isinstance(self.sybil_identities, bool) or not isinstance(self.sybil_identities, int):
            raise ValueError(f"sybil_identities must be an integer, got {self.sybil_identities!r}")
        check_in("sybil_identities", self.sybil_identities, 1, 1000)
        if not isinstance(self.replay_restamped, bool):
            raise ValueError(f"replay_restamped must be a bool, got {self.replay_restamped!r}")

    @property
    def any(self) -> bool:
        """Whether any report is made wrong."""
        return max(self.offset_share, self.replay_share, self.sybil_share) > 0.0


def _raised(r: FrictionReport, by: float, **changes: object) -> FrictionReport:
    hi = REPORT_MU_RANGE[1]
    return replace(
        r, mu=min(hi, r.mu + by), lower_mu=min(hi, r.lower_mu + by),
        upper_mu=min(hi, r.upper_mu + by), **changes,  # type: ignore[arg-type]
    )


def corrupt(
    reports: Sequence[FrictionReport], wrong: WrongReports, rng: np.random.Generator
) -> list[FrictionReport]:
    """``reports`` with the wrong ones of ``wrong`` mixed in (honest ones unchanged).

    Draws, in this order: one uniform per distinct sender (offset senders, in order of first
    appearance), one per report (replay), one per report (Sybil copy). No draw when a share is 0,
    so that a run without wrong reports draws nothing.

    Examples
    --------
    >>> rs = [FrictionReport.numeric(float(i), 0.5, 0.025, sender=f"v{i}") for i in range(4)]
    >>> out = corrupt(rs, WrongReports(sybil_share=1.0, sybil_identities=3),
    ...               np.random.default_rng(0))
    >>> len(out), len({r.sender for r in out})
    (16, 16)
    """
    senders = list(dict.fromkeys(r.sender for r in reports))
    offset_senders: set[str] = set()
    if wrong.offset_share > 0.0 and senders:
        draws = rng.random(len(senders))
        offset_senders = {s for s, u in zip(senders, draws, strict=True) if u < wrong.offset_share}
    out: list[FrictionReport] = []
    replay = (
        rng.random(len(reports)) < wrong.replay_share
        if wrong.replay_share > 0.0 else np.zeros(len(reports), dtype=bool)
    )
    for r, is_replay in zip(reports, replay, strict=True):
        if r.sender in offset_senders:
            r = _raised(r, wrong.offset)
        if is_replay:
            stamp = r.t_created_s if wrong.replay_restamped else r.t_created_s - wrong.replay_age_s
            r = _raised(r, wrong.replay_drop, t_created_s=stamp)
        out.append(r)
    if wrong.sybil_share > 0.0:
        copied = rng.random(len(reports)) < wrong.sybil_share
        for i, r in enumerate(reports):
            if copied[i]:
                out.extend(
                    _raised(r, wrong.offset, sender=f"sybil-{i}-{k}")
                    for k in range(wrong.sybil_identities)
                )
    return out
