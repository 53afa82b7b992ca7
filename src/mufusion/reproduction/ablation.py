"""What each of the authors' settings does on its own: one setting at a time on the paper's text.

For every variant with authors' settings (:attr:`Variant.settings`), each setting is applied
alone to its paper-text baseline and run with the configurations it can reach among
:data:`ABLATION_CONFIGS`; the baseline and the full authors' variant come from the reproduction's
own runs. :func:`ablation_tables` grades every run from its log
(:func:`~mufusion.reproduction.graded.graded_outcome`) and :func:`effect_lines` says, per setting,
what changed against the baseline, computed from those numbers.

Running it is ``mufusion reproduce --ablation`` (docs/authors-settings.md has a recorded run).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mufusion.campaign import RunSpec
from mufusion.configurations import Configuration
from mufusion.reproduction.authors import Setting
from mufusion.reproduction.graded import GradedOutcome, graded_outcome
from mufusion.reproduction.variants import VARIANTS, Variant, variant
from mufusion.sim.log import load_run

C = Configuration

ABLATION_CONFIGS: dict[str, tuple[Configuration, ...]] = {
    "turn": (C.GT, C.L, C.F),
    "popup": (C.GT, C.L, C.P, C.F),
}
"""Configurations run per setting: the turn's lane keepers and the slider L; in the pop-up also P,
whose collision is the paper's outcome there."""


def ablation_key(base: Variant, setting: Setting) -> str:
    """Variant key of the run that applies ``setting`` alone to ``base`` (``turn-paper+tires``)."""
    return f"{base.key}+{setting.key}"


def authors_variants() -> tuple[Variant, ...]:
    """The variants that apply authors' settings to a paper-text baseline."""
    return tuple(v for v in VARIANTS if v.settings and v.baseline)


def ablation_specs() -> list[RunSpec]:
    """The runs of the ablation (baselines and full variants are the reproduction's own).

    Examples
    --------
    >>> specs = ablation_specs()
    >>> specs[0].variant, specs[0].config
    ('turn-paper+pure-arc', 'GT')
    """
    specs = []
    for var in authors_variants():
        base = variant(str(var.baseline))
        for setting in var.settings:
            for config in ABLATION_CONFIGS[var.scenario]:
                if config in setting.reaches:
                    specs.append(RunSpec(scenario=var.scenario, config=config.value,
                                         variant=ablation_key(base, setting),
                                         overrides=(*base.overrides, *setting.overrides)))
    return specs


@dataclass(frozen=True)
class AblationRow:
    """One line of an ablation table: a setting (``None``: the baseline or all settings)."""

    label: str
    setting: Setting | None
    outcomes: dict[Configuration, GradedOutcome]


@dataclass(frozen=True)
class AblationTable:
    """The ablation of one authors' variant: baseline, one row per setting, all settings."""

    variant: Variant
    configs: tuple[Configuration, ...]
    rows: tuple[AblationRow, ...]

    @property
    def baseline(self) -> AblationRow:
        return self.rows[0]


def _graded(runs: Sequence[Mapping[str, Any]]) -> dict[tuple[str, str], GradedOutcome]:
    graded = {}
    for run in runs:
        path = run.get("log")
        if path and Path(path).is_dir():
            graded[(str(run["variant"]), str(run["config"]))] = graded_outcome(load_run(Path(path)))
    return graded


def _row(label: str, key: str, setting: Setting | None, configs: Sequence[Configuration],
         graded: Mapping[tuple[str, str], GradedOutcome]) -> AblationRow:
    return AblationRow(label, setting, {c: graded[(key, c.value)] for c in configs
                                        if (key, c.value) in graded})


def ablation_tables(
    runs: Sequence[Mapping[str, Any]], ablation_runs: Sequence[Mapping[str, Any]]
) -> list[AblationTable]:
    """One :class:`AblationTable` per authors' variant whose runs are present.

    Parameters
    ----------
    runs
        The reproduction's runs (``variant``, ``config``, ``log``): baselines and full variants.
    ablation_runs
        The runs of :func:`ablation_specs`, same keys.
    """
    graded = _graded([*runs, *ablation_runs])
    tables = []
    for var in authors_variants():
        base = variant(str(var.baseline))
        configs = ABLATION_CONFIGS[var.scenario]

        rows = [_row("paper text (baseline)", base.key, None, configs, graded)]
        rows += [_row(f"+ {s.label}", ablation_key(base, s), s, configs, graded)
                 for s in var.settings]
        rows.append(_row("all: the authors' variant", var.key, None, configs, graded))
        if rows[0].outcomes:
            tables.append(AblationTable(var, configs, tuple(rows)))
    return tables


def cell(outcome: GradedOutcome | None, scenario: str) -> str:
    """A compact table cell: lane excursion, peak front utilisation and the yes/no outcomes."""
    if outcome is None:
        return "= baseline"
    parts = [f"exc {outcome.lane_excursion_m:+.2f} m", f"|d| {outcome.max_abs_offset_m:.2f}",
             f"u {outcome.peak_util_front:.2f}"]
    if scenario == "popup":
        if outcome.collision:
            parts.append(f"hit {outcome.impact_speed_mps:.1f} m/s")
        else:
            clearance = outcome.min_clearance_m
            parts.append("no pass" if clearance is None else f"clr {clearance:.2f}")
    else:
        parts.append("opposing" if outcome.entered_opposing_lane
                     else "out" if outcome.left_lane else "in lane")
    return ", ".join(parts)


def _verdict(outcome: GradedOutcome, scenario: str) -> str:
    if scenario == "popup":
        return "collides" if outcome.collision else "passes"
    if outcome.entered_opposing_lane:
        return "enters the opposing lane"
    return "leaves its lane" if outcome.left_lane else "stays in its lane"


def effect_lines(table: AblationTable) -> list[str]:
    """One sentence per setting: what it changed for each configuration against the baseline.

    An outcome that flips (lane, opposing lane, collision) is named; otherwise the largest
    changes of the graded numbers are given.
    """
    scenario = table.variant.scenario
    base = table.baseline.outcomes
    lines = []
    for row in table.rows[1:]:
        effects = []
        for config in table.configs:
            new, old = row.outcomes.get(config), base.get(config)
            if old is None:
                continue
            if new is None:
                effects.append(f"{config.value} unaffected (the setting does not reach it)")
                continue
            was, now = _verdict(old, scenario), _verdict(new, scenario)
            change = f"{now} (was: {was})" if now != was else now
            numbers = [f"excursion {new.lane_excursion_m:+.2f} m "
                       f"({new.lane_excursion_m - old.lane_excursion_m:+.2f})",
                       f"peak front utilisation {new.peak_util_front:.2f} "
                       f"({new.peak_util_front - old.peak_util_front:+.2f})"]
            if scenario == "popup" and new.min_clearance_m is not None:
                numbers.append(f"clearance {new.min_clearance_m:.2f} m")
            if scenario == "popup" and new.collision:
                numbers.append(f"impact {new.impact_speed_mps:.1f} m/s")
            effects.append(f"{config.value} {change}; " + ", ".join(numbers))
        lines.append(f"- **{row.label.removeprefix('+ ')}**: " + "; ".join(effects) + ".")
    return lines
