"""The friction-estimation configurations of the paper (Sec. IV-B) and ours: one definition each.

Every list of configuration names in the package (scenario files, campaigns, the reproduction,
figures, the CLI) derives from :class:`Configuration`; nothing else spells them out.
"""

from __future__ import annotations

from enum import Enum
from typing import Literal

FusionMode = Literal["paper", "safe"]


class Configuration(str, Enum):
    """A friction source the planner can drive on.

    The value is the short name used in files, tables and on the command line.
    """

    GT = "GT"
    L = "L"
    P = "P"
    F = "F"
    F_SAFE = "F-safe"
    F_SHARED = "F+shared"
    F_SAFE_SHARED = "F-safe+shared"

    @property
    def label(self) -> str:
        """Legend text, e.g. ``"F (fused, paper mode)"``."""
        return f"{self.value} ({_DESCRIPTIONS[self]})"

    @property
    def description(self) -> str:
        """What the planner gets, in a few words."""
        return _DESCRIPTIONS[self]

    @property
    def fusion_mode(self) -> FusionMode | None:
        """The GP fusion mode of a fused configuration; None for GT, L and P."""
        return _FUSION_MODES.get(self)

    @property
    def in_paper(self) -> bool:
        """Whether the paper evaluates this configuration (F-safe and the shared ones are ours)."""
        return self in (Configuration.GT, Configuration.L, Configuration.P, Configuration.F)

    @property
    def shares_reports(self) -> bool:
        """Whether the fusion also reads shared reports of other vehicles (decision 0060)."""
        return self in _WITHOUT_REPORTS

    @property
    def without_reports(self) -> Configuration:
        """The same configuration without shared reports (itself if it reads none)."""
        return _WITHOUT_REPORTS.get(self, self)

    @classmethod
    def parse(cls, name: str | Configuration) -> Configuration:
        """The configuration named ``name``.

        Raises
        ------
        ValueError
            If ``name`` is not one of the names, which the message lists.

        Examples
        --------
        >>> Configuration.parse("F-safe").fusion_mode
        'safe'
        """
        if isinstance(name, Configuration):
            return name
        try:
            return cls(name)
        except ValueError:
            raise ValueError(
                f"configuration must be one of {list(CONFIGURATION_NAMES)}, got {name!r}"
            ) from None

    def __str__(self) -> str:
        return self.value


_DESCRIPTIONS: dict[Configuration, str] = {
    Configuration.GT: "ground truth",
    Configuration.L: "local only",
    Configuration.P: "predictive only",
    Configuration.F: "fused, paper mode",
    Configuration.F_SAFE: "fused, safe mode",
    Configuration.F_SHARED: "fused with shared reports, paper mode",
    Configuration.F_SAFE_SHARED: "fused with shared reports, safe mode",
}
_FUSION_MODES: dict[Configuration, FusionMode] = {
    Configuration.F: "paper",
    Configuration.F_SAFE: "safe",
    Configuration.F_SHARED: "paper",
    Configuration.F_SAFE_SHARED: "safe",
}
_WITHOUT_REPORTS: dict[Configuration, Configuration] = {
    Configuration.F_SHARED: Configuration.F,
    Configuration.F_SAFE_SHARED: Configuration.F_SAFE,
}

CONFIGURATION_NAMES: tuple[str, ...] = tuple(c.value for c in Configuration)
"""Every name: ``("GT", "L", "P", "F", "F-safe", "F+shared", "F-safe+shared")``."""

STANDARD_CONFIGURATIONS: tuple[Configuration, ...] = tuple(
    c for c in Configuration if not c.shares_reports
)
"""The configurations a single vehicle runs on its own sensors (GT, L, P, F, F-safe): the default
set of campaigns and the reproduction. The shared ones need reports (a fleet or a reports file)."""

STANDARD_CONFIGURATION_NAMES: tuple[str, ...] = tuple(c.value for c in STANDARD_CONFIGURATIONS)
"""Their names: ``("GT", "L", "P", "F", "F-safe")``."""

PAPER_CONFIGURATIONS: tuple[Configuration, ...] = tuple(c for c in Configuration if c.in_paper)
"""The configurations the paper evaluates."""
