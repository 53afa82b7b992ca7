"""The campaign file: scenarios × configurations × a parameter grid × seeds, as validated TOML.

Everything that would make two runs of one campaign the same run (a scenario, configuration or
grid value listed twice, a grid key also fixed by ``overrides``) is rejected when the file is
read, before anything runs, with a message naming the key and the value.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated, Literal, get_args

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from mufusion.configurations import STANDARD_CONFIGURATION_NAMES
from mufusion.configurations.plugins import (
    CONTROLLERS,
    PLANNERS,
    check_component_spec,
    check_friction_spec,
)

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

Engine = Literal["pool", "ray"]
"""Where a campaign's runs execute (``--engine``; :mod:`mufusion.campaign.engines`)."""
ENGINES: tuple[str, ...] = get_args(Engine)

GridValue = bool | int | float | str
"""A value of one grid key, as TOML gives it."""

GridEntry = GridValue | list[GridValue]
"""One value of a grid axis: a scalar, or on a zipped axis one value per key."""


def axis_keys(axis: str) -> tuple[str, ...]:
    """The scenario keys a grid axis sets: one, or several joined by commas (a zipped axis).

    Examples
    --------
    >>> axis_keys(" friction.mu_before, friction.mu_turn ")
    ('friction.mu_before', 'friction.mu_turn')
    """
    return tuple(part.strip() for part in axis.split(","))

MAX_SEEDS = 100_000


class CampaignFile(BaseModel):
    """A campaign as a TOML file.

    Example::

        name = "friction sweep"
        scenarios = ["popup"]
        configs = ["GT", "P", "F", "F-safe"]  # or a plug-in: "mypkg.estimators:SlipRLS"
        # planner = "mypkg.planners:MyMPC"    # optional: a planner / controller plug-in
        overrides = ["duration_s=4"]          # applied to every run
        seeds = 20                            # optional: every variant with 20 seeds
        [grid]                                # every combination becomes one variant
        "friction.mu" = [0.7, 0.8, 0.9, 1.0]
        "obstacle.distance_m" = [18.0, 22.0]
        # A zipped axis: keys joined by commas take their values together, one list per value
        # (a drop and a rise, never the constant-friction pairs a product would add).
        "friction.mu_before, friction.mu_turn" = [[0.9, 0.3], [0.3, 0.9]]

    With ``seeds = N`` every variant runs with the scenario's ``seed`` field set to
    ``s0, s0 + 1, …, s0 + N − 1``, ``s0`` being the seed the scenario (after ``overrides`` and the
    grid point) declares; the seed drives the ``random`` error models of the estimators.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    name: str = "campaign"
    scenarios: list[str] = Field(min_length=1)
    configs: list[str] = Field(
        default_factory=lambda: list(STANDARD_CONFIGURATION_NAMES), min_length=1
    )
    overrides: list[str] = Field(default_factory=list)
    grid: dict[str, list[GridEntry]] = Field(default_factory=dict)
    seeds: Annotated[int, Field(ge=1, le=MAX_SEEDS)] | None = None
    planner: str | None = None
    """A planner plug-in for every run (``module:Class`` or an entry point); None: the package's."""
    controller: str | None = None
    """A controller plug-in for every run; None: the package's."""

    @field_validator("scenarios")
    @classmethod
    def _distinct_scenarios(cls, v: list[str]) -> list[str]:
        _reject_repeats("scenarios", v)
        return v

    @field_validator("configs")
    @classmethod
    def _known_configs(cls, v: list[str]) -> list[str]:
        for config in v:
            try:
                check_friction_spec(config)
            except ValueError as err:
                raise ValueError(f"configs: {err}") from None
        _reject_repeats("configs", v)
        return v

    @field_validator("planner")
    @classmethod
    def _usable_planner(cls, v: str | None) -> str | None:
        return None if v is None else check_component_spec(v, PLANNERS)

    @field_validator("controller")
    @classmethod
    def _usable_controller(cls, v: str | None) -> str | None:
        return None if v is None else check_component_spec(v, CONTROLLERS)

    @field_validator("overrides")
    @classmethod
    def _distinct_override_keys(cls, v: list[str]) -> list[str]:
        _reject_repeats("overrides keys", [_key_of(item) for item in v])
        return v

    @field_validator("grid")
    @classmethod
    def _distinct_grid_values(cls, v: dict[str, list[GridEntry]]) -> dict[str, list[GridEntry]]:
        empty = [k for k, values in v.items() if not values]
        if empty:
            raise ValueError(f"grid axes {empty} have no values")
        all_keys = [key for axis in v for key in axis_keys(axis)]
        if any(not key for key in all_keys):
            raise ValueError(f"grid axes {[a for a in v if '' in axis_keys(a)]} have an empty key")
        _reject_repeats("grid keys", all_keys)
        for axis, values in v.items():
            width = len(axis_keys(axis))
            # bool is an int in Python; keep True apart from 1 (they are different TOML values).
            seen: set[tuple[tuple[bool, GridValue], ...]] = set()
            for value in values:
                tag = tuple((isinstance(x, bool), x) for x in _entry_values(axis, width, value))
                if tag in seen:
                    raise ValueError(f"grid {axis!r}: value {value!r} is listed more than once")
                seen.add(tag)
        return v

    def axes(self) -> list[tuple[tuple[str, ...], list[tuple[GridValue, ...]]]]:
        """The grid's axes in file order: the keys each sets and its values (one tuple each).

        Examples
        --------
        >>> c = CampaignFile(scenarios=["turn"], grid={"vehicle": ["car"], "a, b": [[1, 2]]})
        >>> c.axes()
        [(('vehicle',), [('car',)]), (('a', 'b'), [(1, 2)])]
        """
        return [(axis_keys(axis), [_entry_values(axis, len(axis_keys(axis)), value)
                                   for value in values])
                for axis, values in self.grid.items()]

    @model_validator(mode="after")
    def _grid_keys_not_fixed_elsewhere(self) -> CampaignFile:
        fixed = {_key_of(item) for item in self.overrides}
        for key in (k for axis in self.grid for k in axis_keys(axis)):
            if key in fixed:
                raise ValueError(
                    f"grid key {key!r} is also set in overrides; keep it in one place"
                )
            if key == "seed" and self.seeds is not None:
                raise ValueError("grid key 'seed' and seeds = N both set the seed; use one")
        return self


def _entry_values(axis: str, width: int, value: GridEntry) -> tuple[GridValue, ...]:
    """A grid value as one value per key of its axis; raises ValueError naming the axis."""
    if width == 1:
        if isinstance(value, list):
            raise ValueError(f"grid {axis!r}: value {value!r} is a list; only a zipped axis "
                             "(keys joined by commas) takes lists")
        return (value,)
    if not isinstance(value, list) or len(value) != width:
        raise ValueError(f"grid {axis!r}: value {value!r} must be a list of {width} values, "
                         f"one per key")
    return tuple(value)


def _key_of(override: str) -> str:
    return override.partition("=")[0].strip()


def _reject_repeats(what: str, values: list[str]) -> None:
    seen: set[str] = set()
    for value in values:
        if value in seen:
            raise ValueError(f"{what}: {value!r} is listed more than once")
        seen.add(value)


def load_campaign(path: str | Path) -> CampaignFile:
    """Read and validate a campaign file.

    Parameters
    ----------
    path
        TOML file with the fields of :class:`CampaignFile`.

    Returns
    -------
    CampaignFile
        The validated campaign.

    Raises
    ------
    ValueError
        If the file is missing, not TOML, or a field is invalid or repeats a value (the message
        names the field and the value).
    """
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"campaign file {str(path)!r} does not exist")
    try:
        raw = tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise ValueError(f"campaign file {str(path)!r} is not valid TOML: {err}") from None
    try:
        return CampaignFile.model_validate(raw)
    except ValidationError as err:
        problems = "; ".join(
            f"{'.'.join(str(p) for p in e['loc']) or '(top level)'}: {e['msg']}"
            for e in err.errors()
        )
        raise ValueError(f"invalid campaign {str(path)!r}: {problems}") from None
