"""Reading scenarios: built-in TOML files or the user's, with ``--set dotted.key=value`` overrides.

Every error is a ``ValueError`` naming the file or the key and what is allowed, raised before any
simulation starts: an unknown key (also one another scenario kind has but this one does not use),
a key given twice, a value of the wrong type (a boolean is not a number) or outside its range.
"""

from __future__ import annotations

import dataclasses
import json
import sys
from importlib import resources
from pathlib import Path
from typing import Any

from pydantic import BaseModel, TypeAdapter, ValidationError

from mufusion.planner.safety import SafetySettings
from mufusion.scenarios.config import SCENARIO_KINDS, AnyScenario, ScenarioConfig
from mufusion.sim.faults import Fault
from mufusion.sim.settings import LaneRecoverySettings, ProbingSettings

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

BUILTIN_SCENARIOS: tuple[str, ...] = tuple(
    kind for kind in SCENARIO_KINDS
    if resources.files("mufusion.scenarios").joinpath(f"{kind}.toml").is_file()
)
"""The kinds that ship a scenario file of their own (``turn``, ``popup``; a ``road`` needs the
user's)."""
_ADAPTER: TypeAdapter[AnyScenario] = TypeAdapter(ScenarioConfig)


def _format_validation_error(err: ValidationError, source: str) -> str:
    lines = [f"invalid scenario {source}:"]
    for e in err.errors():
        # The first location element of a tagged union is the kind's tag ("turn", "popup").
        loc = [str(p) for p in e["loc"]]
        if loc and loc[0] in SCENARIO_KINDS:
            loc = loc[1:]
        where = ".".join(loc) or "(top level)"
        lines.append(f"  {where}: {e['msg']}")
    return "\n".join(lines)


def scenario_from_dict(
    data: dict[str, Any], source: str = "<dict>"
) -> AnyScenario:
    """Validate a scenario mapping.

    Raises
    ------
    ValueError
        With one line per invalid field, each naming its dotted key and the allowed range.
    """
    if not isinstance(data.get("name"), str) or data["name"] not in SCENARIO_KINDS:
        raise ValueError(
            f"invalid scenario {source}:\n  name: must be one of {list(SCENARIO_KINDS)}, "
            f"got {data.get('name')!r}"
        )
    try:
        return _ADAPTER.validate_python(data)
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
            return tomllib.loads(path.read_text(encoding="utf-8")), f"file {str(path)!r}"
        except UnicodeDecodeError:
            raise ValueError(f"scenario file {str(path)!r} is not a UTF-8 text file") from None
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

    The keys are checked against the schema of the scenario's kind (``data["name"]``, which an
    override may itself change).

    Raises
    ------
    ValueError
        If an override is not of the form ``key=value``, a key is given twice, or a key is not
        in the schema of the scenario's kind (the message lists the keys there).
    """
    out = json.loads(json.dumps(data))
    parsed: list[tuple[list[str], str, str]] = []
    seen: set[str] = set()
    for item in overrides:
        key, sep, raw = item.partition("=")
        parts = [p for p in key.strip().split(".") if p]
        if not sep or not parts:
            raise ValueError(f"--set expects dotted.key=value, got {item!r}")
        dotted = ".".join(parts)
        if dotted in seen:
            raise ValueError(f"--set {dotted!r} is given more than once")
        seen.add(dotted)
        parsed.append((parts, raw, item))
    for parts, raw, _ in parsed:
        if parts == ["name"]:
            out["name"] = _parse_value(raw)
    kind = SCENARIO_KINDS.get(str(out.get("name")))
    if kind is None:
        raise ValueError(f"name must be one of {list(SCENARIO_KINDS)}, got {out.get('name')!r}")
    for parts, raw, item in parsed:
        _check_key(kind, parts, item)
        node = out
        for p in parts[:-1]:
            if not isinstance(node.get(p), dict):
                node[p] = {}
            node = node[p]
        node[parts[-1]] = _parse_value(raw)
    return out


def _fields(model: type | None) -> dict[str, Any]:
    """Field name → annotation of a pydantic model or a dataclass (empty for anything else)."""
    if isinstance(model, type) and issubclass(model, BaseModel):
        return {name: f.annotation for name, f in model.model_fields.items()}
    if model is not None and dataclasses.is_dataclass(model):
        return {f.name: f.type for f in dataclasses.fields(model)}
    return {}


def _check_key(kind: type[BaseModel], parts: list[str], item: str) -> None:
    model: type | None = kind
    for i, p in enumerate(parts):
        fields = _fields(model)
        if p not in fields:
            allowed = sorted(fields)
            where = ".".join(parts[:i]) or "top level"
            scenario = kind.model_fields["name"].annotation.__args__[0]  # type: ignore[union-attr]
            raise ValueError(
                f"--set {item!r}: unknown key {'.'.join(parts[: i + 1])!r} for the "
                f"{scenario!r} scenario; keys at {where}: {', '.join(allowed)}"
            )
        model = _submodel(fields[p])


def _submodel(annotation: Any) -> type | None:
    """The model (pydantic or dataclass) an annotation holds, also inside ``X | None``."""
    if isinstance(annotation, str):
        annotation = _DATACLASS_NAMES.get(annotation)
    candidates = [annotation, *(getattr(annotation, "__args__", ()) or ())]
    for arg in candidates:
        if isinstance(arg, type) and (issubclass(arg, BaseModel) or dataclasses.is_dataclass(arg)):
            if arg is not list:
                return arg
    return None


# Dataclass annotations are strings under `from __future__ import annotations`.
_DATACLASS_NAMES: dict[str, type] = {
    c.__name__: c for c in (SafetySettings, Fault, ProbingSettings, LaneRecoverySettings)
}


def load_scenario(
    name_or_path: str | Path, overrides: list[str] | None = None
) -> AnyScenario:
    """Load a built-in scenario (``"turn"``, ``"popup"``) or a TOML file, with overrides applied.

    Raises
    ------
    ValueError
        Unknown scenario, unreadable file, unknown or repeated override key, or an invalid field
        (the message names the dotted key and the allowed range).

    Examples
    --------
    >>> load_scenario("popup", ["obstacle.distance_m=25"]).obstacle.distance_m
    25.0
    >>> load_scenario("turn", ["friction.mu=0.3"])
    Traceback (most recent call last):
    ...
    ValueError: --set 'friction.mu=0.3': unknown key 'friction.mu' for the 'turn' scenario; keys at friction: change_ahead_m, mu_before, mu_turn
    """  # noqa: E501
    raw, source = _raw_scenario(name_or_path)
    return scenario_from_dict(apply_overrides(raw, overrides or []), source)
