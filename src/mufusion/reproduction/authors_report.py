"""The report's section on the authors' settings: side by side, setting by setting, the slide.

Per scenario with an authors' variant: the graded outcomes of the paper-text and the authors'
variant next to each other, the settings that differ, the ablation (one setting at a time,
:mod:`mufusion.reproduction.ablation`) when it was run, and what the variant cannot represent.
Then, for the turn, why L leaves its lane or not, in each variant, from its log
(:mod:`mufusion.reproduction.slide`). Every number is read from a log.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from mufusion.configurations import Configuration
from mufusion.reproduction.ablation import (
    ablation_tables,
    authors_variants,
    cell,
    effect_lines,
)
from mufusion.reproduction.graded import graded_outcome
from mufusion.reproduction.slide import slide_diagnosis, slide_text
from mufusion.reproduction.variants import Variant, variant
from mufusion.sim.log import RunLog, load_run

ABLATION_COMMAND = "mufusion reproduce --ablation"


def _table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(str(c).replace("|", "\\|") for c in row) + " |" for row in rows]
    return [*lines, ""]


def _logs(runs: Sequence[Mapping[str, Any]]) -> dict[tuple[str, Configuration], RunLog]:
    logs = {}
    for run in runs:
        path = run.get("log")
        if path and Path(path).is_dir():
            logs[(str(run["variant"]), Configuration.parse(str(run["config"])))] = load_run(
                Path(path)
            )
    return logs


def _side_by_side(base: Variant, var: Variant, logs) -> list[str]:
    rows = []
    for config in Configuration:
        pair = [logs.get((v.key, config)) for v in (base, var)]
        if all(p is None for p in pair):
            continue
        rows.append([config.value, *(cell(graded_outcome(p), var.scenario) if p else "—"
                                     for p in pair)])
    return _table(("config", base.title, var.title), rows)


def authors_sections(
    summary: Mapping[str, Any], heading_level: int = 2
) -> list[str]:
    """Markdown lines of the authors' section (empty if no authors' variant was run).

    Parameters
    ----------
    summary
        ``runs`` (the reproduction's) and optionally ``ablation`` (the runs of
        :func:`~mufusion.reproduction.ablation.ablation_specs`), each with ``variant``,
        ``config`` and ``log``.
    heading_level
        Markdown level of the section heading.
    """
    runs = list(summary.get("runs") or [])
    ablation_runs = list(summary.get("ablation") or [])
    logs = _logs(runs)
    present = [v for v in authors_variants() if any(k[0] == v.key for k in logs)]
    if not present:
        return []
    h = "#" * heading_level
    md = [
        f"{h} The authors' settings",
        "",
        "Where the authors' public code set something the paper's text leaves open or states "
        "differently, the *authors* variants use the code's value. Cells: **exc** = farthest "
        "footprint corner beyond the ego lane's edges (negative: room left inside), **|d|** = "
        "largest offset of the centre of gravity, **u** = peak realised front-tire "
        "utilisation; then the outcome (lane, or clearance / impact speed in the pop-up).",
        "",
    ]
    tables = {t.variant.key: t for t in ablation_tables(runs, ablation_runs)}
    for var in present:
        base = variant(str(var.baseline))
        md += [f"{h}# {var.title} against {base.title}", "", *_side_by_side(base, var, logs)]
        md += ["Settings that differ:", ""]
        md += _table(("setting", "paper text (our default)", "authors' code"),
                     [(s.label, s.paper, s.authors) for s in var.settings])
        table = tables.get(var.key)
        if table is None:
            md += [f"One setting at a time: not run here (`{ABLATION_COMMAND}` runs it; "
                   "docs/authors-settings.md records a run).", ""]
        else:
            md += ["One setting at a time, each applied alone to the paper-text variant "
                   "(\"= baseline\": the setting does not reach that configuration):", ""]
            md += _table(("setting", *(c.value for c in table.configs)),
                         [(row.label, *(cell(row.outcomes.get(c), var.scenario)
                                        for c in table.configs)) for row in table.rows])
            md += ["What each setting does:", "", *effect_lines(table), ""]
        md += ["Not represented:", "", *(f"- {text}" for text in var.unrepresented), ""]
    md += _slide_section(logs, h)
    return md


def _slide_section(logs: Mapping[tuple[str, Configuration], RunLog], h: str) -> list[str]:
    turn_keys = [key for key, config in logs
                 if config is Configuration.L and variant(key).scenario == "turn"]
    if not turn_keys:
        return []
    md = [f"{h}# Why L leaves its lane in the turn, or why not", "",
          "From each run's log (figures \"slide\" in the variant sections: planned front force "
          "over the true friction circle, realised front utilisation, lateral deviation and "
          "body slip against time).", ""]
    for key in turn_keys:
        md += [f"**{variant(key).title}.** "
               f"{slide_text(slide_diagnosis(logs[(key, Configuration.L)]))}", ""]
    return md
