"""The reproduction report: our outcomes next to the paper's, figures, safe fusion mode, timing.

Written as Markdown and converted to HTML with Python-Markdown (its ``tables`` extension). Every
verdict comes from :mod:`mufusion.reproduction.verdicts`; a criterion that differs gets a
paragraph: the explanation computed from the logs if there is one, otherwise a plain statement of
what differs and by how much.
"""

from __future__ import annotations

import html
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import markdown

from mufusion.configurations import Configuration
from mufusion.metrics import TABLE_COLUMNS, format_cell
from mufusion.reproduction.authors_report import authors_sections
from mufusion.reproduction.variants import (
    CLEARANCE_TOLERANCE_M,
    IMPACT_SPEED_TOLERANCE_MPS,
    UTILIZATION_TOLERANCE,
    VARIANTS,
    Variant,
)
from mufusion.reproduction.verdicts import Outcome, compare_with_paper, fmt

FIGURE_CAPTIONS: dict[str, str] = {
    "snapshots": "Top views at the paper's positions: vehicle footprint, planned trajectory, "
    "obstacle when active; road surface coloured by the true friction (cf. paper Fig. 3a-h, "
    "4a-h).",
    "traces": "Distance to the lane centre and speed against progress, one line per "
    "configuration; lane boundaries and obstacle marked (cf. paper Fig. 3i-j, 4i-j).",
    "forces": "Planned front tire forces at the comparison instant against each "
    "configuration's force-limit polygon and the true friction circle (cf. paper Fig. 3k, 4k).",
    "estimate": "Fused friction estimate of the F configuration at the comparison instant: "
    "true μ, input data with margins, posterior mean and 95 % band, μ̂ used by the planner "
    "(cf. paper Fig. 3l, 4l).",
    "animation": "Animated top view of the run.",
    "slide": "The slide mechanism against time: L's (and GT's, F's) executed planned front force "
    "over the true friction circle μ_gt F_z, realised front utilisation, lateral deviation and "
    "body slip; dotted: the local estimate becomes available (cf. paper Sec. IV-C).",
}
"""Caption per figure kind; figure keys are ``"<variant key>/<kind>"`` or
``"<variant key>/<config>/animation"``."""


def _caption(key: str, in_section: bool) -> str:
    parts = key.split("/")
    text = FIGURE_CAPTIONS.get(parts[-1], "")
    if not text:
        return key
    if in_section:
        return f"{parts[1]}: {text}" if len(parts) == 3 else text
    return f"{'/'.join(parts[:-1])}: {text}"


def _table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> list[str]:
    def cell(text: str) -> str:
        return str(text).replace("|", "\\|")

    lines = ["| " + " | ".join(cell(h) for h in header) + " |",
             "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(cell(c) for c in row) + " |" for row in rows]
    return [*lines, ""]


_OUTCOME_COLUMNS = [c for c in TABLE_COLUMNS if c.key not in ("variant",)]


def _outcome_table(runs: Sequence[Mapping[str, Any]]) -> list[str]:
    return _table([c.header for c in _OUTCOME_COLUMNS],
                  [[format_cell(r.get(c.key), c) for c in _OUTCOME_COLUMNS] for r in runs])


def _group(runs: Sequence[Mapping[str, Any]]) -> list[tuple[Variant, list[Mapping[str, Any]]]]:
    for run in runs:
        for key in ("variant", "config"):
            if key not in run:
                raise ValueError(f"every run in summary['runs'] needs {key!r}; got {sorted(run)}")
    groups = []
    for var in VARIANTS:
        members = [r for r in runs if r["variant"] == var.key]
        if members:
            groups.append((var, members))
    unknown = {str(r["variant"]) for r in runs} - {v.key for v, _ in groups}
    if unknown:
        raise ValueError(f"runs of unknown variants {sorted(unknown)}")
    return groups


def build_report_markdown(
    summary: Mapping[str, Any],
    out_dir: Path,
    figures: Mapping[str, Path],
    explanations: Mapping[str, str] | None = None,
) -> str:
    """The report as Markdown text; see :func:`write_report`."""
    runs = summary.get("runs")
    if not isinstance(runs, list) or not runs:
        raise ValueError("summary['runs'] must be a non-empty list of run dicts")
    explanations = dict(explanations or {})
    groups = _group(runs)
    figure_number = 0
    used: set[str] = set()

    def figure_lines(keys: Sequence[str], in_section: bool) -> list[str]:
        nonlocal figure_number
        lines: list[str] = []
        for key in keys:
            figure_number += 1
            used.add(key)
            rel = Path(os.path.relpath(Path(figures[key]).resolve(), Path(out_dir).resolve()))
            lines += [f"![Figure {figure_number}]({rel.as_posix()})", "",
                      f"*Figure {figure_number}: {_caption(key, in_section)}*", ""]
        return lines

    all_verdicts = [v for run in runs for v in compare_with_paper(run)]
    agree = sum(v.outcome is Outcome.AGREES for v in all_verdicts)
    md = [
        "# mufusion reproduction report",
        "",
        f"{len(runs)} runs in {fmt(summary.get('elapsed_s'), 's', 0)} (wall clock). "
        f"{agree} of {len(all_verdicts)} criteria agree with the paper "
        "(Svensson & Törngren, Section IV).",
        "",
        "Verdicts are computed from each run's metrics against the paper's reported outcomes; "
        f"tolerances: impact speed ±{IMPACT_SPEED_TOLERANCE_MPS:g} m/s, clearance "
        f"±{CLEARANCE_TOLERANCE_M:g} m, utilisation ±{100 * UTILIZATION_TOLERANCE:.0f} "
        "percentage points. Numeric criteria apply to the paper's vehicle (the truck) only; the "
        "car variants are checked for the qualitative outcome.",
        "",
    ]
    for var, group in groups:
        md += [f"## {var.title}", "", "### Outcomes", "", *_outcome_table(group)]
        verdicts = [v for r in group for v in compare_with_paper(r)]
        if verdicts:
            md += ["### Comparison with the paper", ""]
            md += _table(("config", "criterion", "paper", "ours", "verdict"),
                         [(v.config.value, v.criterion, v.paper, v.ours, v.outcome.value)
                          for v in verdicts])
            for v in verdicts:
                if v.outcome is Outcome.AGREES:
                    continue
                text = explanations.get(v.key) or (
                    f"{v.difference}. No explanation recorded for this difference."
                )
                md += [f"**{v.config.value}, {v.criterion} ({v.outcome.value}).** {text}", ""]
        keys = [k for k in figures if k.split("/", 1)[0] == var.key]
        if keys:
            md += ["### Figures", "", *figure_lines(keys, in_section=True)]

    md += authors_sections(summary)
    md += ["## Safe fusion mode (F-safe)", ""]
    fused = (Configuration.F.value, Configuration.F_SAFE.value)
    safe_groups = [(v, g) for v, g in groups if any(r["config"] == fused[1] for r in g)]
    if not safe_groups:
        md += ["No F-safe runs in this summary.", ""]
    for var, group in safe_groups:
        md += [f"### {var.title}", "", *_outcome_table([r for r in group if r["config"] in fused])]

    md += ["## Timing", "",
           "Wall-clock time per planning step (not deterministic; depends on the machine).", ""]
    md += _table(
        ("variant", "config", "median [ms]", "p99 [ms]", "fallbacks"),
        [(str(r["variant"]), str(r["config"]), fmt(r.get("planner_median_ms"), digits=1),
          fmt(r.get("planner_p99_ms"), digits=1), fmt(r.get("fallbacks"))) for r in runs],
    )
    md += [f"Total wall-clock time of the campaign: {fmt(summary.get('elapsed_s'), 's', 1)}.", ""]
    rest = [k for k in figures if k not in used]
    if rest:
        md += ["## Other figures", "", *figure_lines(rest, in_section=False)]
    return "\n".join(md).rstrip() + "\n"


_STYLE = (
    "body{font-family:sans-serif;max-width:70em;margin:2em auto;padding:0 1em;}"
    "table{border-collapse:collapse;margin:0.5em 0 1em;font-size:0.9em;}"
    "th,td{border:1px solid #bbb;padding:0.2em 0.5em;text-align:left;}"
    "th{background:#eee;} img{max-width:100%;}"
)


def markdown_to_html(text: str, title: str = "mufusion report") -> str:
    """A standalone HTML page of Markdown ``text`` (Python-Markdown with tables)."""
    body = markdown.markdown(text, extensions=["tables"], output_format="html")
    return (
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
        f"<title>{html.escape(title)}</title>\n<style>{_STYLE}</style>\n</head>\n<body>\n"
        f"{body}\n</body>\n</html>\n"
    )


def write_report(
    summary: Mapping[str, Any],
    out_dir: str | Path,
    figures: Mapping[str, Path],
    explanations: Mapping[str, str] | None = None,
) -> tuple[Path, Path]:
    """Write ``report.md`` and ``report.html`` comparing the runs with the paper.

    Per variant: a table of outcomes, a table of criteria with the paper's value, ours and a
    computed verdict, a paragraph for every criterion that does not agree, and the variant's
    figures with captions. Then the safe fusion mode (F vs F-safe) and the planner timing.

    Parameters
    ----------
    summary : mapping
        ``runs``: list of dicts with ``variant`` (a variant key), ``config`` and the run's
        metrics; ``elapsed_s``: total wall-clock time [s]; optionally ``ablation``: the runs
        of :func:`~mufusion.reproduction.ablation.ablation_specs` (same keys), shown in the
        section on the authors' settings.
    out_dir : str or Path
        Directory of the report (created if needed); images are linked relative to it.
    figures : mapping of str to Path
        Figure files keyed ``"<variant key>/<kind>"`` (see :data:`FIGURE_CAPTIONS`); other keys
        are listed at the end.
    explanations : mapping of str to str, optional
        Text for a criterion that differs, keyed by :attr:`Verdict.key`.

    Returns
    -------
    (Path, Path)
        The Markdown and the HTML file.

    Raises
    ------
    ValueError
        If ``summary['runs']`` is missing or empty, a run lacks variant/config or names an
        unknown variant, or a figure file does not exist.
    """
    out = Path(out_dir)
    for key, file in figures.items():
        if not Path(file).is_file():
            raise ValueError(f"figures[{key!r}] = {str(file)!r} does not exist")
    text = build_report_markdown(summary, out, figures, explanations)
    out.mkdir(parents=True, exist_ok=True)
    md_path, html_path = out / "report.md", out / "report.html"
    md_path.write_text(text, encoding="utf-8")
    html_path.write_text(markdown_to_html(text), encoding="utf-8")
    return md_path, html_path
