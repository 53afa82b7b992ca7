"""The reproduction report: our outcomes next to the paper's, figures, safe fusion mode, timing.

The paper's facts (Section IV of Svensson & Törngren) are written down once here, in
``PAPER_FACTS`` and the tolerances below; every verdict is computed from the run's metrics and
these facts, never written by hand. A criterion that differs gets a paragraph: the caller's
explanation if one is given, otherwise a plain statement of what differs and by how much.
"""

from __future__ import annotations

import html
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

# Tolerances of the numeric comparisons (the paper gives approximate values: "~17.5 m/s",
# "~0.5 m"; utilisation to 0.1 %).
IMPACT_SPEED_TOLERANCE_MPS = 2.5
CLEARANCE_TOLERANCE_M = 0.3
UTILIZATION_TOLERANCE = 0.05  # absolute, in fractions (5 percentage points)
PAPER_IMPACT_SPEED_MPS = 17.5
PAPER_CLEARANCE_M = 0.5
# Planned-force utilisation relative to GT in the pop-up scenario (Sec. IV-D): the authors'
# configuration (μ = 0.89) and the same rules at the paper's stated μ = 1.0.
PAPER_UTILIZATION_VS_GT: dict[str, dict[str, float]] = {
    "authors": {"P": -0.326, "F": -0.056},
    "paper": {"P": -0.40, "F": -0.05},
}

AGREES, DIFFERS, NO_DATA = "agrees", "differs", "no data"
_PAPER_CONFIGS = ("GT", "L", "P", "F")


@dataclass(frozen=True)
class Verdict:
    """One criterion of one run compared with the paper."""

    scenario: str
    variant: str
    config: str
    criterion: str
    paper: str
    ours: str
    verdict: str
    difference: str

    @property
    def key(self) -> str:
        """The explanation key ``"<scenario>/<variant>/<config>/<criterion>"``."""
        return f"{self.scenario}/{self.variant}/{self.config}/{self.criterion}"


def _fmt(value: Any, unit: str = "", digits: int = 2) -> str:
    if value is None:
        return "—"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return f"{value:.{digits}f}{(' ' + unit) if unit else ''}"
    return str(value)


def _pct(value: float | None) -> str:
    return "—" if value is None else f"{100 * value:+.1f} %"


def _utilization_reference(variant: str) -> dict[str, float] | None:
    v = variant.lower()
    if "0.89" in v or "author" in v:
        return PAPER_UTILIZATION_VS_GT["authors"]
    if "1.0" in v or v.startswith("paper"):
        return PAPER_UTILIZATION_VS_GT["paper"]
    return None


def _is_paper_vehicle(variant: str) -> bool:
    # The paper simulates a truck; our "car" variants check the qualitative outcome only.
    return "car" not in variant.lower()


def _flag(run: Mapping[str, Any], scenario: str, variant: str, config: str, criterion: str,
          metric: str, expected: bool, paper: str) -> Verdict:
    ours = run.get(metric)
    if ours is None:
        return Verdict(scenario, variant, config, criterion, paper, "—", NO_DATA,
                       f"our run has no value for {metric}")
    ok = bool(ours) == expected
    diff = "" if ok else (
        f"{metric} is {_fmt(bool(ours))}, the paper's outcome needs {_fmt(expected)}"
    )
    return Verdict(scenario, variant, config, criterion, paper, f"{metric} = {_fmt(bool(ours))}",
                   AGREES if ok else DIFFERS, diff)


def _number(run: Mapping[str, Any], scenario: str, variant: str, config: str, criterion: str,
            metric: str, target: float, tolerance: float, unit: str, paper: str,
            as_percent: bool = False) -> Verdict:
    ours = run.get(metric)
    show = _pct if as_percent else (lambda v: _fmt(v, unit))
    if ours is None:
        return Verdict(scenario, variant, config, criterion, paper, "—", NO_DATA,
                       f"our run has no value for {metric}")
    delta = float(ours) - target
    ok = abs(delta) <= tolerance
    if as_percent:
        diff_text = f"{100 * delta:+.1f} percentage points (tolerance ±{100 * tolerance:.0f} pp)"
    else:
        diff_text = f"{delta:+.2f} {unit} (tolerance ±{tolerance:g} {unit})"
    return Verdict(scenario, variant, config, criterion, paper, f"{metric} = {show(ours)}",
                   AGREES if ok else DIFFERS,
                   "" if ok else f"{metric} is {show(ours)} vs the paper's {show(target)}: "
                   f"{diff_text}")


def compare_with_paper(run: Mapping[str, Any]) -> list[Verdict]:
    """Verdicts of one run against the paper's outcomes (Section IV, Fig. 3 and Fig. 4).

    Criteria: turn — L enters the opposing lane, GT/P/F stay in their lane; pop-up — P collides
    (at ≈ 17.5 m/s), GT/L/F do not and pass with ≈ 0.5 m clearance, planned-force utilisation
    relative to GT (P −32.6 %, F −5.6 % for the authors' μ = 0.89; −40 % and −5 % at μ = 1.0).
    Numeric criteria apply to the paper's vehicle only (variants without "car"). Configurations
    the paper does not have (F-safe) get no verdicts.

    Parameters
    ----------
    run : mapping
        ``scenario``, ``variant``, ``config`` and the keys of ``RunMetrics.to_dict()``.

    Returns
    -------
    list of Verdict
        Possibly empty.

    Raises
    ------
    ValueError
        If ``scenario``, ``variant`` or ``config`` is missing.
    """
    for key in ("scenario", "variant", "config"):
        if key not in run:
            raise ValueError(f"run must have a {key!r} entry; got keys {sorted(run)}")
    scenario, variant, config = str(run["scenario"]), str(run["variant"]), str(run["config"])
    if config not in _PAPER_CONFIGS:
        return []
    args = (run, scenario, variant, config)
    numeric = _is_paper_vehicle(variant)
    verdicts: list[Verdict] = []
    if scenario == "turn":
        if config == "L":
            verdicts.append(_flag(*args, "opposing lane", "entered_opposing_lane", True,
                                  "leaves its lane into the opposing lane"))
        else:
            verdicts.append(_flag(*args, "stays in lane", "left_lane", False, "stays in its lane"))
    elif scenario == "popup":
        if config == "P":
            verdicts.append(_flag(*args, "collision", "collision", True, "collides"))
            if numeric:
                verdicts.append(_number(*args, "impact speed", "impact_speed_mps",
                                        PAPER_IMPACT_SPEED_MPS, IMPACT_SPEED_TOLERANCE_MPS, "m/s",
                                        f"≈ {PAPER_IMPACT_SPEED_MPS} m/s"))
        else:
            verdicts.append(_flag(*args, "collision", "collision", False, "passes, no collision"))
            if numeric:
                verdicts.append(_number(*args, "clearance", "min_clearance_m", PAPER_CLEARANCE_M,
                                        CLEARANCE_TOLERANCE_M, "m", f"≈ {PAPER_CLEARANCE_M} m"))
        reference = _utilization_reference(variant) if numeric else None
        if reference is not None and config in reference:
            verdicts.append(_number(*args, "utilisation vs GT", "utilization_vs_gt",
                                    reference[config], UTILIZATION_TOLERANCE, "",
                                    _pct(reference[config]), as_percent=True))
    return verdicts


_FIGURE_CAPTIONS = {
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
}


def _tag(scenario: str, variant: str) -> str:
    # Same naming as mufusion.plots.run_figures.reproduction_figures.
    return f"{scenario}-{''.join(c if c.isalnum() else '-' for c in variant)}".lower()


def _caption(key: str, in_section: bool) -> str:
    parts = key.split("/")
    text = _FIGURE_CAPTIONS.get(parts[-1], "")
    if not text:
        return key
    if in_section:
        # "<tag>/<kind>" or "<tag>/<config>/animation": the section already names the tag.
        return f"{parts[1]}: {text}" if len(parts) == 3 else text
    return f"{'/'.join(parts[:-1])}: {text}"


def _table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> list[str]:
    def cell(text: str) -> str:
        return str(text).replace("|", "\\|")

    lines = ["| " + " | ".join(cell(h) for h in header) + " |",
             "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(cell(c) for c in row) + " |" for row in rows]
    return [*lines, ""]


_OUTCOME_HEADER = ("config", "collision", "impact speed", "min clearance", "max |d|",
                   "left lane", "opposing lane", "utilisation vs GT", "max force excess",
                   "fallbacks")


def _outcome_row(run: Mapping[str, Any]) -> list[str]:
    return [
        str(run["config"]),
        _fmt(run.get("collision")),
        _fmt(run.get("impact_speed_mps"), "m/s"),
        _fmt(run.get("min_clearance_m"), "m"),
        _fmt(run.get("max_abs_lateral_offset_m"), "m"),
        _fmt(run.get("left_lane")),
        _fmt(run.get("entered_opposing_lane")),
        _pct(run.get("utilization_vs_gt")),
        _pct(run.get("max_force_excess")),
        _fmt(run.get("fallbacks")),
    ]


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
    groups: dict[tuple[str, str], list[Mapping[str, Any]]] = {}
    for run in runs:
        for key in ("scenario", "variant", "config"):
            if key not in run:
                raise ValueError(f"every run in summary['runs'] needs {key!r}; got {sorted(run)}")
        groups.setdefault((str(run["scenario"]), str(run["variant"])), []).append(run)

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
    agree = sum(v.verdict == AGREES for v in all_verdicts)
    md = [
        "# mufusion reproduction report",
        "",
        f"{len(runs)} runs in {_fmt(summary.get('elapsed_s'), 's', 0)} (wall clock). "
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
    for (scenario, variant), group in groups.items():
        md += [f"## {scenario}, {variant}", "", "### Outcomes", ""]
        md += _table(_OUTCOME_HEADER, [_outcome_row(r) for r in group])
        verdicts = [v for r in group for v in compare_with_paper(r)]
        if verdicts:
            md += ["### Comparison with the paper", ""]
            md += _table(("config", "criterion", "paper", "ours", "verdict"),
                         [(v.config, v.criterion, v.paper, v.ours, v.verdict) for v in verdicts])
            for v in verdicts:
                if v.verdict == AGREES:
                    continue
                text = explanations.get(v.key) or (
                    f"{v.difference}. No explanation recorded for this difference."
                )
                md += [f"**{v.config}, {v.criterion} ({v.verdict}).** {text}", ""]
        keys = [k for k in figures if k.split("/", 1)[0] == _tag(scenario, variant)]
        if keys:
            md += ["### Figures", "", *figure_lines(keys, in_section=True)]

    md += ["## Safe fusion mode (F-safe)", ""]
    safe_groups = [(sv, g) for sv, g in groups.items() if any(r["config"] == "F-safe" for r in g)]
    if not safe_groups:
        md += ["No F-safe runs in this summary.", ""]
    for (scenario, variant), group in safe_groups:
        md += [f"### {scenario}, {variant}", ""]
        md += _table(_OUTCOME_HEADER,
                     [_outcome_row(r) for r in group if r["config"] in ("F", "F-safe")])

    md += ["## Timing", "",
           "Wall-clock time per planning step (not deterministic; depends on the machine).", ""]
    md += _table(
        ("scenario", "variant", "config", "median [ms]", "p99 [ms]", "fallbacks"),
        [(str(r["scenario"]), str(r["variant"]), str(r["config"]),
          _fmt(r.get("planner_median_ms"), digits=1), _fmt(r.get("planner_p99_ms"), digits=1),
          _fmt(r.get("fallbacks"))) for r in runs],
    )
    md += [f"Total wall-clock time of the campaign: {_fmt(summary.get('elapsed_s'), 's', 1)}.",
           ""]
    rest = [k for k in figures if k not in used]
    if rest:
        md += ["## Other figures", "", *figure_lines(rest, in_section=False)]
    return "\n".join(md).rstrip() + "\n"


_IMAGE = re.compile(r"^!\[(?P<alt>[^\]]*)\]\((?P<src>[^)]+)\)$")


def _inline(text: str) -> str:
    out = html.escape(text, quote=False)
    out = re.sub(r"\*\*(.+?)\*\*", r"<strong>\1</strong>", out)
    out = re.sub(r"(?<![\w*])\*(?!\s)(.+?)(?<!\s)\*(?![\w*])", r"<em>\1</em>", out)
    return re.sub(r"`([^`]+)`", r"<code>\1</code>", out)


def _split_row(line: str) -> list[str]:
    cells = re.split(r"(?<!\\)\|", line.strip()[1:-1])
    return [c.strip().replace("\\|", "|") for c in cells]


def markdown_to_html(markdown: str, title: str = "mufusion report") -> str:
    """Convert the report's Markdown subset to a standalone HTML page.

    Handles what :func:`build_report_markdown` writes: ``#`` headings, pipe tables, images on
    their own line, paragraphs with ``**bold**``, ``*italic*`` and ``code`` spans.
    """
    body: list[str] = []
    blocks = re.split(r"\n\s*\n", markdown.strip())
    for block in blocks:
        lines = block.splitlines()
        first = lines[0]
        heading = re.match(r"^(#{1,6})\s+(.*)$", first)
        image = _IMAGE.match(first.strip())
        if heading and len(lines) == 1:
            level = len(heading.group(1))
            body.append(f"<h{level}>{_inline(heading.group(2))}</h{level}>")
        elif image and len(lines) == 1:
            src = html.escape(image.group("src"), quote=True)
            alt = html.escape(image.group("alt"), quote=True)
            body.append(f'<p><img src="{src}" alt="{alt}"></p>')
        elif all(line.startswith("|") for line in lines) and len(lines) >= 2:
            header, rows = _split_row(lines[0]), [_split_row(line) for line in lines[2:]]
            cells = "".join(f"<th>{_inline(c)}</th>" for c in header)
            body.append(f"<table>\n<thead><tr>{cells}</tr></thead>\n<tbody>")
            for row in rows:
                body.append("<tr>" + "".join(f"<td>{_inline(c)}</td>" for c in row) + "</tr>")
            body.append("</tbody>\n</table>")
        else:
            body.append(f"<p>{_inline(' '.join(line.strip() for line in lines))}</p>")
    style = (
        "body{font-family:sans-serif;max-width:70em;margin:2em auto;padding:0 1em;}"
        "table{border-collapse:collapse;margin:0.5em 0 1em;font-size:0.9em;}"
        "th,td{border:1px solid #bbb;padding:0.2em 0.5em;text-align:left;}"
        "th{background:#eee;} img{max-width:100%;}"
    )
    return (
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
        f"<title>{html.escape(title)}</title>\n<style>{style}</style>\n</head>\n<body>\n"
        + "\n".join(body)
        + "\n</body>\n</html>\n"
    )


def write_report(
    summary: Mapping[str, Any],
    out_dir: str | Path,
    figures: Mapping[str, Path],
    explanations: Mapping[str, str] | None = None,
) -> tuple[Path, Path]:
    """Write ``report.md`` and ``report.html`` comparing the runs with the paper.

    Per scenario and variant: a table of outcomes, a table of criteria with the paper's value,
    ours and a computed verdict ("agrees", "differs", "no data"), a paragraph for every criterion
    that does not agree, and the figures of that scenario and variant with captions. Then the
    safe fusion mode (F vs F-safe) and the planner timing.

    Parameters
    ----------
    summary : mapping
        ``runs``: list of dicts with ``scenario``, ``variant``, ``config`` and the keys of
        ``RunMetrics.to_dict()``; ``elapsed_s``: total wall-clock time [s].
    out_dir : str or Path
        Directory of the report (created if needed); images are linked relative to it.
    figures : mapping of str to Path
        Figure files keyed ``"<scenario>-<variant>/<kind>"`` as written by
        :func:`mufusion.plots.run_figures.reproduction_figures`; other keys are listed at the end.
    explanations : mapping of str to str, optional
        Text for a criterion that differs, keyed ``"<scenario>/<variant>/<config>/<criterion>"``
        (see :attr:`Verdict.key`). Without one, the report states which metric differs and by
        how much.

    Returns
    -------
    (Path, Path)
        The Markdown and the HTML file.

    Raises
    ------
    ValueError
        If ``summary['runs']`` is missing or empty, a run lacks scenario/variant/config, or a
        figure file does not exist.
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
