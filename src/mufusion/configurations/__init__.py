"""The friction sources the planner can drive on: GT, L, P, F and F-safe (paper Sec. IV-B).

The layer between estimation and planning: each configuration combines the emulated estimators
(:mod:`mufusion.estimators`) and, for F and F-safe, the GP fusion (:mod:`mufusion.fusion`) into
one ``step`` that returns a :class:`FrictionEstimate` over the grid ahead.
"""

from mufusion.configurations.registry import (
    CONFIGURATION_NAMES,
    PAPER_CONFIGURATIONS,
    Configuration,
)
from mufusion.configurations.sources import (
    MU_HAT_MAX,
    MU_HAT_MIN,
    FrictionConfiguration,
    FrictionEstimate,
    make_configuration,
)

__all__ = [
    "CONFIGURATION_NAMES",
    "MU_HAT_MAX",
    "MU_HAT_MIN",
    "PAPER_CONFIGURATIONS",
    "Configuration",
    "FrictionConfiguration",
    "FrictionEstimate",
    "make_configuration",
]
