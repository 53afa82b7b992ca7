"""The runs behind ``mufusion reproduce``: every variant with every configuration."""

from __future__ import annotations

from mufusion.campaign import RunSpec, with_indices
from mufusion.configurations import STANDARD_CONFIGURATIONS
from mufusion.reproduction.variants import VARIANTS


def reproduction_specs(include_car: bool = True) -> list[RunSpec]:
    """One run per variant and configuration (truck variants first; the car ones optional).

    Examples
    --------
    >>> len(reproduction_specs(include_car=False))
    20
    """
    return with_indices([
        RunSpec(scenario=v.scenario, config=c.value, variant=v.key, overrides=v.overrides)
        for v in VARIANTS
        if include_car or v.paper_vehicle
        for c in STANDARD_CONFIGURATIONS
    ])
