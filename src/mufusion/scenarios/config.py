"""Scenario configuration: validated (pydantic) models of the TOML files shipped with the package.

Every field can be overridden with ``--set dotted.key=value`` on the command line
(:func:`apply_overrides`); an unknown key or a value outside its range is a clear error naming the
key, never a traceback from deep inside the simulator.
"""

from __future__ import annotations

import json
import sys
from importlib import resources
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ErrorModel = Literal["none", "worst_over", "worst_under", "random"]

PositiveFloat = Annotated[float, Field(gt=0.0, allow_inf_nan=False)]
NonNegFloat = Annotated[float, Field(ge=0.0, allow_inf_nan=False)]
Friction = Annotated[float, Field(gt=0.0, le=1.5, allow_inf_nan=False)]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, validate_default=True)


class RoadConfig(_Strict):
    lane_width_m: Annotated[float, Field(ge=2.5, le=5.0)] = 3.5
    approach_m: Annotated[float, Field(ge=10.0, le=500.0)] = 60.0
    """Straight road behind the vehicle's start position (room for the start and the look-back)."""
    length_m: Annotated[float, Field(ge=50.0, le=2000.0)] = 300.0
    """Total length of a straight road (``popup``) or of the straight after the turn (``turn``)."""


class TurnConfig(_Strict):
    radius_m: Annotated[float, Field(ge=10.0, le=500.0)] = 28.0
    angle_rad: Annotated[float, Field(gt=0.0, le=3.2)] = 1.5707963267948966
    direction: Literal["left", "right"] = "right"
    """Right-hand traffic: in a right turn the outside of the curve is the opposing lane."""
    start_ahead_m: Annotated[float, Field(ge=0.0, le=200.0)] = 20.0
    """Distance from the vehicle's start to the beginning of the curve (its entry clothoid)."""
    clothoid_m: Annotated[float, Field(ge=0.0, le=50.0)] = 5.0


class FrictionConfig(_Strict):
    mu: Friction = 1.0
    """Friction everywhere (``popup``)."""
    mu_before: Friction = 0.8
    """Friction before the change point (``turn``)."""
    mu_turn: Friction = 0.4
    """Friction from the change point on (``turn``)."""
    change_ahead_m: Annotated[float, Field(ge=-50.0, le=200.0)] = 0.0
    """Where the friction changes, relative to the vehicle's start (paper: at s = 0)."""


class ObstacleConfig(_Strict):
    distance_m: Annotated[float, Field(gt=0.0, le=200.0)] = 20.0
    """Distance from the vehicle's front to the obstacle's centre when it appears."""
    lateral_offset_m: Annotated[float, Field(ge=-5.0, le=5.0)] = 0.0
    """Offset of the obstacle centre from the lane centre (left positive)."""
    length_m: PositiveFloat = 1.0
    width_m: PositiveFloat = 1.0
    appear_at_s: NonNegFloat = 0.0
    """Time at which it appears [s]."""


class EstimationConfig(_Strict):
    local_error: ErrorModel = "none"
    predictive_error: ErrorModel = "none"
    initial_local_mu: Friction | None = None
    """The local estimator's held value before it first becomes available; ``None``: what it
    measured (with its error model) on the road under the vehicle just before the run starts."""
    length_scale_m: Annotated[float, Field(gt=0.0, le=500.0)] | None = None
    """GP length scale; ``None`` keeps the fusion's default."""


class PlannerSettings(_Strict):
    horizon_steps: Annotated[int, Field(ge=10, le=80)] = 40
    dt_s: Annotated[float, Field(gt=0.01, le=0.5)] = 0.1
    utilization_factor: Annotated[float, Field(gt=0.0, le=1.0)] = 0.9
    backend: Literal["acados", "casadi"] = "acados"
    use_sampling: bool = True
    rate_hz: Annotated[float, Field(ge=1.0, le=50.0)] = 10.0


class SimSettings(_Strict):
    plant_rate_hz: Annotated[float, Field(ge=200.0, le=2000.0)] = 200.0
    controller_rate_hz: Annotated[float, Field(ge=50.0, le=500.0)] = 50.0


class ScenarioConfig(_Strict):
    """One closed-loop experiment: road, friction, obstacle, vehicle, estimation, solver."""

    name: Literal["turn", "popup"]
    description: str = ""
    vehicle: Literal["truck", "car"] = "truck"
    initial_speed_mps: Annotated[float, Field(gt=0.0, le=40.0)] = 12.0
    reference_speed_mps: Annotated[float, Field(gt=0.0, le=40.0)] | None = None
    """Cruise speed the planner tracks; defaults to the initial speed."""
    duration_s: Annotated[float, Field(gt=0.0, le=120.0)] = 10.0
    seed: Annotated[int, Field(ge=0)] = 0
    emergency_on_obstacle: bool = False
    """Switch the planner to its emergency (stop) mode when an obstacle appears."""
    road: RoadConfig = RoadConfig()
    turn: TurnConfig = TurnConfig()
    friction: FrictionConfig = FrictionConfig()
    obstacle: ObstacleConfig | None = None
    estimation: EstimationConfig = EstimationConfig()
    planner: PlannerSettings = PlannerSettings()
    sim: SimSettings = SimSettings()

    @model_validator(mode="after")
    def _check(self) -> ScenarioConfig:
        if self.name == "popup" and self.obstacle is None:
            raise ValueError("obstacle: the popup scenario needs an [obstacle] table")
        return self

    @property
    def cruise_speed_mps(self) -> float:
        return self.reference_speed_mps or self.initial_speed_mps


BUILTIN_SCENARIOS: tuple[str, ...] = ("turn", "popup")


def _format_validation_error(err: ValidationError, source: str) -> str:
    lines = [f"invalid scenario {source}:"]
    for e in err.errors():
        loc = ".".join(str(p) for p in e["loc"]) or "(top level)"
        lines.append(f"  {loc}: {e['msg']}")
    return "\n".join(lines)


def scenario_from_dict(data: dict[str, Any], source: str = "<dict>") -> ScenarioConfig:
    """Validate a scenario mapping.

    Raises
    ------
    ValueError
        With one line per invalid field, each naming its dotted key and the allowed range.
    """
    try:
        return ScenarioConfig.model_validate(data)
    except ValidationError as err:
        raise ValueError(_format_validation_error(err, source)) from None


def _raw_builtin(name: str) -> dict[str, Any]:
    if name not in BUILTIN_SCENARIOS:
        raise ValueError(
            f"scenario must be one of {list(BUILTIN_SCENARIOS)} or a .toml path, got {name!r}"
        )
    text = resources.files("mufusion.scenarios").joinpath(f"{name}.toml").read_text()
    return tomllib.loads(text)


def _raw_scenario(name_or_path: str | Path) -> tuple[dict[str, Any], str]:
    path = Path(name_or_path)
    if path.suffix == ".toml":
        if not path.is_file():
            raise ValueError(f"scenario file {str(path)!r} does not exist")
        try:
            return tomllib.loads(path.read_text()), str(path)
        except tomllib.TOMLDecodeError as err:
            raise ValueError(f"scenario file {str(path)!r} is not valid TOML: {err}") from None
    return _raw_builtin(str(name_or_path)), f"'{name_or_path}'"


def _parse_value(text: str) -> Any:
    # TOML/JSON literals first (numbers, booleans, quoted strings, arrays); a bare word is a string.
    # "none" is a value of the error-model fields; only "null" clears an optional field.
    lowered = text.strip()
    if lowered == "null":
        return None
    try:
        return json.loads(lowered)
    except json.JSONDecodeError:
        pass
    try:
        return tomllib.loads(f"v = {lowered}")["v"]
    except tomllib.TOMLDecodeError:
        return lowered


def apply_overrides(data: dict[str, Any], overrides: list[str]) -> dict[str, Any]:
    """Return a copy of ``data`` with ``dotted.key=value`` overrides applied.

    Raises
    ------
    ValueError
        If an override is not of the form ``key=value`` or names a key the schema does not have.
    """
    out = json.loads(json.dumps(data))
    for item in overrides:
        if "=" not in item:
            raise ValueError(f"--set expects dotted.key=value, got {item!r}")
        key, _, raw = item.partition("=")
        parts = [p for p in key.strip().split(".") if p]
        if not parts:
            raise ValueError(f"--set expects dotted.key=value, got {item!r}")
        _check_key(parts, item)
        node = out
        for p in parts[:-1]:
            if not isinstance(node.get(p), dict):
                node[p] = {}
            node = node[p]
        node[parts[-1]] = _parse_value(raw)
    return out


def _check_key(parts: list[str], item: str) -> None:
    model: type[BaseModel] | None = ScenarioConfig
    for i, p in enumerate(parts):
        if model is None or p not in model.model_fields:
            allowed = sorted(model.model_fields) if model is not None else []
            where = ".".join(parts[:i]) or "top level"
            raise ValueError(
                f"--set {item!r}: unknown key {'.'.join(parts[: i + 1])!r}; "
                f"keys at {where}: {', '.join(allowed)}"
            )
        annotation = model.model_fields[p].annotation
        model = _submodel(annotation)


def _submodel(annotation: Any) -> type[BaseModel] | None:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in getattr(annotation, "__args__", ()) or ():
        if isinstance(arg, type) and issubclass(arg, BaseModel):
            return arg
    return None


def load_scenario(name_or_path: str | Path, overrides: list[str] | None = None) -> ScenarioConfig:
    """Load a built-in scenario (``"turn"``, ``"popup"``) or a TOML file, with overrides applied.

    Raises
    ------
    ValueError
        Unknown scenario, unreadable file, unknown override key, or an invalid field (the message
        names the dotted key and the allowed range).

    Examples
    --------
    >>> load_scenario("popup", ["obstacle.distance_m=25"]).obstacle.distance_m
    25.0
    """
    raw, source = _raw_scenario(name_or_path)
    return scenario_from_dict(apply_overrides(raw, overrides or []), source)
