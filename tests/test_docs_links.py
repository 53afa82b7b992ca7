"""The docs stay a usable reference: links resolve, citations name what exists, pages stay short.

Checked on the repository's own files: every relative markdown link under docs/ and in README.md
points to an existing file; every ``docs/decisions/NNNN`` cited anywhere names an existing
decision record; a ``docs/<page>.md, "Title"`` citation in code, examples or the README names text
that the page contains; no page in docs/ is longer than 400 lines and docs/experiments.md (the
current results) stays under 60 KB; CI (.ci/run) runs README's test command, as written there.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
MAX_LINES = 400
MAX_EXPERIMENTS_BYTES = 60_000

# [text](target) and ![alt](target); the target ends at the first space or closing parenthesis.
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
DECISION = re.compile(r"docs/decisions/(\d{4})\b")
PAGE_CITATION = re.compile(r"docs/([\w/.-]+\.md),?\s+(?:section\s+)?\"([^\"]+)\"")
CODE_DIRS = ("src", "tests", "benchmarks", "examples")
CODE_SUFFIXES = {".py", ".pyx", ".toml", ".md", ".sh", ".cfg"}

MARKDOWN = sorted([*DOCS.rglob("*.md"), ROOT / "README.md"])
PAGES = sorted(DOCS.rglob("*.md"))


def relative_links(text: str) -> list[str]:
    """Targets of the markdown links in ``text`` that point into the repository."""
    out = []
    for target in LINK.findall(text):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
            continue  # a URL (http:, mailto:) or an anchor on the same page
        out.append(target.split("#", 1)[0])
    return out


def _code_files() -> list[Path]:
    files = [ROOT / "README.md"]
    for name in CODE_DIRS:
        files += [p for p in (ROOT / name).rglob("*") if p.is_file() and p.suffix in CODE_SUFFIXES]
    return sorted(files)


def _joined(text: str) -> str:
    """The text with line breaks and the comment markers after them folded into spaces."""
    return re.sub(r"\s*\n\s*(?:#+\s|//\s*)?", " ", text)


def test_link_finder_sees_relative_links_and_skips_urls() -> None:
    text = "[a](b.md) ![f](figures/x.png) [u](https://x.org/a.md) [s](#top) [c](c.md#part)"
    assert relative_links(text) == ["b.md", "figures/x.png", "c.md"]


@pytest.mark.parametrize("path", MARKDOWN, ids=lambda p: str(p.relative_to(ROOT)))
def test_relative_links_resolve(path: Path) -> None:
    broken = [t for t in relative_links(path.read_text()) if not (path.parent / t).exists()]
    assert not broken, f"{path.relative_to(ROOT)} links to missing files: {broken}"


@pytest.mark.parametrize("path", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_page_over_the_line_limit(path: Path) -> None:
    lines = len(path.read_text().splitlines())
    assert lines <= MAX_LINES, f"{path.relative_to(ROOT)} has {lines} lines (at most {MAX_LINES})"


def test_current_results_stay_short() -> None:
    size = len((DOCS / "experiments.md").read_bytes())
    assert size <= MAX_EXPERIMENTS_BYTES, f"docs/experiments.md is {size} bytes"


def test_ci_runs_the_readme_test_command() -> None:
    # README's first code block: the install-and-reproduce command, then the test command.
    block = re.search(r"```bash\n(.*?)```", (ROOT / "README.md").read_text(), re.S)
    assert block is not None
    command = block.group(1).splitlines()[1]
    assert command.startswith("python -m pytest "), command
    ci = (ROOT / ".ci" / "run").read_text().splitlines()
    runs = [line for line in ci if "-m pytest" in line and not line.lstrip().startswith("#")]
    assert len(runs) == 1 and f" {command} >" in runs[0], (command, runs)


def test_cited_decision_records_exist() -> None:
    records = {p.name[:4] for p in (DOCS / "decisions").glob("[0-9][0-9][0-9][0-9]-*.md")}
    missing = []
    for path in [*_code_files(), *MARKDOWN]:
        for num in DECISION.findall(path.read_text()):
            if num not in records:
                missing.append(f"{path.relative_to(ROOT)}: docs/decisions/{num}")
    assert records, "no decision records found"
    assert not missing, f"citations of missing decision records: {missing}"


def test_decision_records_are_indexed() -> None:
    index = (DOCS / "decisions" / "README.md").read_text()
    records = sorted(p.name for p in (DOCS / "decisions").glob("[0-9][0-9][0-9][0-9]-*.md"))
    numbers = [int(name[:4]) for name in records]
    assert numbers == list(range(1, len(records) + 1)), "decision records are not numbered 1..N"
    unindexed = [name for name in records if f"]({name})" not in index]
    assert not unindexed, f"decision records missing from docs/decisions/README.md: {unindexed}"


def test_page_citations_in_code_name_existing_text() -> None:
    stale = []
    for path in _code_files():
        for page, title in PAGE_CITATION.findall(_joined(path.read_text())):
            target = DOCS / page
            wanted = " ".join(title.lstrip("#").split()).lower()
            if not target.exists():
                stale.append(f"{path.relative_to(ROOT)}: docs/{page} does not exist")
            elif wanted not in " ".join(target.read_text().split()).lower():
                stale.append(f"{path.relative_to(ROOT)}: docs/{page} has no {title!r}")
    assert not stale, "citations of text the docs no longer hold:\n" + "\n".join(stale)
