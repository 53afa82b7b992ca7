"""The friction sources the planner can drive on: GT, L, P, F and F-safe (paper Sec. IV-B).

The layer between estimation and planning: each configuration combines the emulated estimators
(:mod:`mufusion.estimators`) and, for F and F-safe, the GP fusion (:mod:`mufusion.fusion`) into
one ``step`` that returns a :class:`FrictionEstimate` over the grid ahead.
"""

from typing import TYPE_CHECKING

from mufusion._lazy import lazy_getattr
from mufusion.configurations.registry import (
    CONFIGURATION_NAMES,
    PAPER_CONFIGURATIONS,
    Configuration,
)

if TYPE_CHECKING:
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

# The sources (and the fusion, SciPy with it) load on first use: checking a --config name or a
# campaign file needs the registry only.
__getattr__ = lazy_getattr(__name__, {
    name: "sources"
    for name in ("MU_HAT_MAX", "MU_HAT_MIN", "FrictionConfiguration", "FrictionEstimate",
                 "make_configuration")
})
