"""Run specifications: what one run of a campaign is, its unique name, and how a campaign file
expands into runs (scenarios × grid points × seeds × configurations, dealt into shards).

Each run is independent and deterministic, so the same list gives the same logs on a laptop (a
process pool), on Ray, or on a cluster (one shard per array job).
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

from mufusion.campaign.schema import CampaignFile, GridValue
from mufusion.scenarios import load_scenario

# A run directory's readable label is cut here; the index in front keeps names unique anyway.
MAX_LABEL_CHARS = 96


@dataclass(frozen=True)
class RunSpec:
    """One run of a campaign.

    Attributes
    ----------
    scenario
        Built-in scenario name or path of a TOML file.
    config
        Friction source: ``GT``, ``L``, ``P``, ``F``, ``F-safe`` or a plug-in's name.
    variant
        Label of the scenario variant (e.g. ``"friction.mu=0.8"``), used in tables and names.
    overrides
        ``dotted.key=value`` overrides applied to the scenario file (the grid point's included).
    seed
        Seed set on the scenario (``seed=…``) when the campaign repeats variants over seeds;
        ``None`` keeps the scenario's own.
    grid
        The grid point as ``(key, value)`` pairs: one column each in the results table.
    index
        Position in the whole campaign (all shards); the run's directory name starts with it.
        ``None`` until assigned (:func:`with_indices`).
    planner, controller
        Plug-ins to plan and control with (``module:attribute`` or an entry point's name);
        ``None``: the package's own.
    """

    scenario: str
    config: str
    variant: str = "default"
    overrides: tuple[str, ...] = field(default_factory=tuple)
    seed: int | None = None
    grid: tuple[tuple[str, GridValue], ...] = field(default_factory=tuple)
    index: int | None = None
    planner: str | None = None
    controller: str | None = None

    @property
    def all_overrides(self) -> list[str]:
        """The overrides with the seed, as given to :func:`~mufusion.scenarios.load_scenario`."""
        if self.seed is None:
            return list(self.overrides)
        # The seed replaces a `seed=` override (the start of the campaign's seeds): a key may
        # be set once only.
        kept = [o for o in self.overrides if o.partition("=")[0].strip() != "seed"]
        return [*kept, f"seed={self.seed}"]

    @property
    def scenario_label(self) -> str:
        """The scenario's name, or a scenario file's stem (never its directory)."""
        path = Path(self.scenario)
        return path.stem if path.suffix == ".toml" else self.scenario

    @property
    def name(self) -> str:
        """The run's directory name: ``<index>-<scenario>-<variant>[-s<seed>]-<config>``.

        Only letters, digits and ``._=+-`` remain, so the name is one path component; the index
        makes it unique even where two labels sanitise alike.

        Raises
        ------
        ValueError
            If the spec has no index yet.

        Examples
        --------
        >>> RunSpec("popup", "GT", "obstacle.lateral_offset_m=-1.0", index=3).name
        '0003-popup-obstacle.lateral_offset_m=-1.0-GT'
        """
        if self.index is None:
            raise ValueError("RunSpec.index is None: assign indices with with_indices(specs)")
        seed = "" if self.seed is None else f"-s{self.seed}"
        label = _sanitise(f"{self.scenario_label}-{self.variant}")[:MAX_LABEL_CHARS]
        return f"{self.index:04d}-{label}{seed}-{_sanitise(self.config)}"


def _sanitise(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9._=+-]+", "_", text).strip("_.") or "run"


def with_indices(specs: Sequence[RunSpec]) -> list[RunSpec]:
    """``specs`` with every missing index set to the spec's position in the list."""
    return [s if s.index is not None else replace(s, index=i) for i, s in enumerate(specs)]


def check_distinct(specs: Iterable[RunSpec]) -> None:
    """Reject two specs that are the same run or would share a directory.

    Raises
    ------
    ValueError
        Naming the repeated run (scenario, variant, seed, config) or directory name.
    """
    runs: set[tuple[str, str, tuple[str, ...]]] = set()
    names: set[str] = set()
    for spec in specs:
        run = (spec.scenario, spec.config, tuple(spec.all_overrides))
        if run in runs:
            raise ValueError(
                f"run {spec.scenario} / {spec.variant} / seed {spec.seed} / {spec.config} "
                "is listed more than once"
            )
        runs.add(run)
        if spec.name in names:
            raise ValueError(f"two runs share the directory name {spec.name!r}")
        names.add(spec.name)


def campaign_specs(
    campaign: CampaignFile, *, shard: int = 0, shards: int = 1
) -> list[RunSpec]:
    """The runs of ``campaign`` that belong to shard ``shard`` of ``shards``.

    Variants are scenario × grid point × seed. A variant is never split: its GT run, which the
    others are compared with, stays in the same shard. Variants are dealt round-robin, so the
    shards of one campaign partition it and each can run as one job of a cluster array; indices
    (and so directory names) are those of the whole campaign.

    Parameters
    ----------
    campaign
        A validated campaign file.
    shard, shards
        Which of how many shards to return (0-based).

    Returns
    -------
    list of RunSpec
        In campaign order: scenario, grid point, seed, configuration.

    Raises
    ------
    ValueError
        If ``shards`` < 1, ``shard`` is not in [0, shards), or a grid key or value is invalid for
        a scenario (checked before anything runs).
    """
    if shards < 1 or not 0 <= shard < shards:
        raise ValueError(f"shard must be in [0, shards) with shards >= 1, got {shard}/{shards}")
    axes = campaign.axes()
    points = list(itertools.product(*(values for _, values in axes))) or [()]
    specs: list[RunSpec] = []
    variant_index = 0
    for scenario in campaign.scenarios:
        for point in points:
            # A zipped axis contributes one (key, value) pair per key: one column each.
            grid = tuple(
                pair
                for (keys, _), values in zip(axes, point, strict=True)
                for pair in zip(keys, values, strict=True)
            )
            overrides = (*campaign.overrides, *(f"{k}={_toml_value(v)}" for k, v in grid))
            cfg = load_scenario(scenario, list(overrides))  # fail before anything runs
            seeds: list[int | None] = (
                [None] if campaign.seeds is None
                else list(range(cfg.seed, cfg.seed + campaign.seeds))
            )
            label = ", ".join(f"{k}={_toml_value(v)}" for k, v in grid) or "default"
            for seed in seeds:
                if variant_index % shards == shard:
                    specs += [
                        RunSpec(
                            scenario=scenario,
                            config=config,
                            variant=label,
                            overrides=overrides,
                            seed=seed,
                            grid=grid,
                            index=variant_index * len(campaign.configs) + c,
                            planner=campaign.planner,
                            controller=campaign.controller,
                        )
                        for c, config in enumerate(campaign.configs)
                    ]
                variant_index += 1
    check_distinct(specs)
    return specs


def _toml_value(v: GridValue) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return v
    return repr(v)
