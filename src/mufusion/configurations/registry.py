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
        """Whether the paper evaluates this configuration (F-safe is ours)."""
        return self is not Configuration.F_SAFE

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
}
_FUSION_MODES: dict[Configuration, FusionMode] = {
    Configuration.F: "paper",
    Configuration.F_SAFE: "safe",
}

CONFIGURATION_NAMES: tuple[str, ...] = tuple(c.value for c in Configuration)
"""The names, in the paper's order: ``("GT", "L", "P", "F", "F-safe")``."""

PAPER_CONFIGURATIONS: tuple[Configuration, ...] = tuple(c for c in Configuration if c.in_paper)
"""The configurations the paper evaluates."""
