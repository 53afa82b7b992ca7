"""The friction sources the planner can drive on: GT, L, P, F and F-safe (paper Sec. IV-B).

The layer between estimation and planning. A friction source reads a sensor frame
(:mod:`mufusion.estimators.sensors`; never the true friction, except GT) and returns a
:class:`FrictionEstimate` over the grid ahead (:mod:`~mufusion.configurations.interface`). The
paper's configurations combine the emulated estimators' reports and, for F and F-safe, the GP
fusion (:mod:`mufusion.fusion`); a source of your own plugs in the same way
(:mod:`~mufusion.configurations.plugins`).
"""

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
    Configuration,
)
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
