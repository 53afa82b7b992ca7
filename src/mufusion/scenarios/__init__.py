"""Built-in scenarios (``turn``, ``popup``) as validated TOML files, the ``road`` kind (any
road), their loader and runner."""

from mufusion.scenarios.config import (
    SCENARIO_KINDS,
    PopupScenario,
    ScenarioConfig,
    TurnScenario,
)
from mufusion.scenarios.loading import (
    BUILTIN_SCENARIOS,
    apply_overrides,
    load_scenario,
    scenario_from_dict,
)
from mufusion.scenarios.road_kind import RoadScenario

__all__ = [
    "BUILTIN_SCENARIOS",
    "SCENARIO_KINDS",
    "PopupScenario",
    "RoadScenario",
    "ScenarioConfig",
    "TurnScenario",
    "apply_overrides",
    "load_scenario",
    "scenario_from_dict",
]
