"""The friction sources the planner can drive on: GT, L, P, F and F-safe (paper Sec. IV-B), and
F+shared and F-safe+shared (the fusion with other vehicles' reports, decision 0060).

The layer between estimation and planning. A friction source reads a sensor frame
(:mod:`mufusion.estimators.sensors`; never the true friction, except GT) and returns a
:class:`FrictionEstimate` over the grid ahead (:mod:`~mufusion.configurations.interface`). The
paper's configurations combine the emulated estimators' reports and, for F and F-safe, the GP
fusion (:mod:`mufusion.fusion`); a source of your own plugs in the same way
(:mod:`~mufusion.configurations.plugins`).
"""

from typing import TYPE_CHECKING

from mufusion._lazy import lazy_getattr
from mufusion.configurations.interface import (
    MU_HAT_MAX,
    MU_HAT_MIN,
    FrictionEstimate,
    FrictionEstimator,
    FrictionSource,
    channels_of,
    step_source,
)
from mufusion.configurations.registry import (
    CONFIGURATION_NAMES,
    PAPER_CONFIGURATIONS,
    STANDARD_CONFIGURATION_NAMES,
    STANDARD_CONFIGURATIONS,
    Configuration,
)

if TYPE_CHECKING:
    from mufusion.configurations.sources import (
        EmulatedConfiguration,
        FrictionConfiguration,
        make_configuration,
        make_estimator,
    )

__all__ = [
    "CONFIGURATION_NAMES",
    "MU_HAT_MAX",
    "MU_HAT_MIN",
    "PAPER_CONFIGURATIONS",
    "STANDARD_CONFIGURATIONS",
    "STANDARD_CONFIGURATION_NAMES",
    "Configuration",
    "EmulatedConfiguration",
    "FrictionConfiguration",
    "FrictionEstimate",
    "FrictionEstimator",
    "FrictionSource",
    "channels_of",
    "make_configuration",
    "make_estimator",
    "step_source",
]

# The paper's sources (and the fusion, SciPy with it) load on first use: checking a --config
# name or a campaign file needs the registry and the interface only.
__getattr__ = lazy_getattr(__name__, {
    name: "sources"
    for name in ("EmulatedConfiguration", "FrictionConfiguration", "make_configuration",
                 "make_estimator")
})
