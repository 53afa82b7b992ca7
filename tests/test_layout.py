"""The package layout is the data flow: imports point upstream only."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "mufusion"
ORDER = [
    "road",
    "vehicle",
    "estimators",
    "fusion",
    "configurations",
    "planner",
    "sim",
    "scenarios",
    "metrics",
    "campaign",
    "reproduction",
    "plots",
    "cli",
]
RANK = {name: i for i, name in enumerate(ORDER)}


def _stage(path: Path) -> str | None:
    rel = path.relative_to(SRC).parts
    head = rel[0].removesuffix(".py")
    return head if head in RANK else None


def _imported_stages(path: Path) -> set[str]:
    tree = ast.parse(path.read_text())
    found: set[str] = set()
    for node in ast.walk(tree):
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [node.module]
        for name in names:
            parts = name.split(".")
            if parts[0] == "mufusion" and len(parts) > 1 and parts[1] in RANK:
                found.add(parts[1])
    return found


FILES = [p for p in SRC.rglob("*.py") if _stage(p) is not None]


@pytest.mark.parametrize("path", FILES, ids=lambda p: str(p.relative_to(SRC)))
def test_imports_point_upstream(path: Path) -> None:
    own = _stage(path)
    for other in _imported_stages(path):
        if other == own:
            continue
        if own != "cli":
            assert other not in {"plots", "cli"}, f"{path}: only the CLI may import {other}"
        assert RANK[other] < RANK[own], f"{path} ({own}) imports downstream stage {other}"


def _module_name(path: Path) -> str:
    rel = path.relative_to(SRC.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _import_graph() -> dict[str, set[str]]:
    """Module → the mufusion modules it imports (type-only imports included)."""
    modules = {_module_name(p): p for p in SRC.rglob("*.py")}
    graph: dict[str, set[str]] = {m: set() for m in modules}
    for name, path in modules.items():
        for node in ast.walk(ast.parse(path.read_text())):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                # `from pkg import sub` imports the module pkg.sub when there is one.
                targets = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            for target in targets:
                if target in modules and target != name:
                    graph[name].add(target)
    return graph


def test_no_import_cycle_between_modules() -> None:
    graph = _import_graph()
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(module: str) -> None:
        state[module] = 1
        stack.append(module)
        for other in sorted(graph[module]):
            if state.get(other) == 1:
                cycle = [*stack[stack.index(other):], other]
                raise AssertionError("import cycle: " + " → ".join(cycle))
            if other not in state:
                visit(other)
        stack.pop()
        state[module] = 2

    for module in sorted(graph):
        if module not in state:
            visit(module)
