"""Built-in scenarios (``turn``, ``popup``) as validated TOML files, and their loader."""

from mufusion.scenarios.config import (
    BUILTIN_SCENARIOS,
    ScenarioConfig,
    apply_overrides,
    load_scenario,
    scenario_from_dict,
)

__all__ = [
    "BUILTIN_SCENARIOS",
    "ScenarioConfig",
    "apply_overrides",
    "load_scenario",
    "scenario_from_dict",
]
