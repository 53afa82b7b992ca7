"""The fusion package's structure: no import cycle, engine-owned caches, validation once."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

import mufusion.fusion as fusion
import mufusion.fusion.assembly as assembly
import mufusion.fusion.data as data_module
from mufusion.fusion import (
    DEFAULT_GRID_M,
    PAPER_PRIOR,
    FusionData,
    GPFusion,
    PosteriorEngine,
    assemble_inputs,
    fuse,
)

PACKAGE = Path(fusion.__file__).parent


def _fusion_imports(path: Path) -> set[str]:
    """Modules of mufusion.fusion imported by ``path``, type-only imports included."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module:
            name = node.module
        elif isinstance(node, ast.Import):
            name = node.names[0].name
        else:
            continue
        parts = name.split(".")
        if parts[:2] == ["mufusion", "fusion"] and len(parts) > 2:
            found.add(parts[2])
    return found


def test_no_import_cycle_within_fusion():
    graph = {p.stem: _fusion_imports(p) for p in PACKAGE.glob("*.py") if p.stem != "__init__"}
    state: dict[str, int] = {}

    def visit(node: str, stack: list[str]) -> None:
        if state.get(node) == 2:
            return
        assert state.get(node) != 1, f"import cycle: {' -> '.join([*stack, node])}"
        state[node] = 1
        for nxt in graph.get(node, ()):
            visit(nxt, [*stack, node])
        state[node] = 2

    for module in graph:
        visit(module, [])


def test_no_file_over_450_lines():
    for path in PACKAGE.glob("*.py"):
        assert len(path.read_text().splitlines()) <= 450, path.name


def test_no_module_level_lru_cache():
    for path in PACKAGE.glob("*.py"):
        assert "lru_cache" not in path.read_text(), path.name


def test_gpfusion_owns_its_engine_cache():
    a = GPFusion(PAPER_PRIOR, DEFAULT_GRID_M)
    b = GPFusion(PAPER_PRIOR, DEFAULT_GRID_M)
    assert a.engine is not b.engine
    a.fuse([0.0, 10.0], [0.4, 0.5], [0.025, 0.1])
    assert a.engine.cached_grids == 1 and b.engine.cached_grids == 0
    a.engine.clear()
    assert a.engine.cached_grids == 0


def test_engine_cache_is_bounded():
    engine = PosteriorEngine(max_grids=2)
    for k in range(5):
        s = np.array([0.0, 1.0 + k])
        engine.latent(PAPER_PRIOR, s, DEFAULT_GRID_M, np.zeros(2), np.full(2, 0.05))
    assert engine.cached_grids == 2
    with pytest.raises(ValueError, match="max_grids"):
        PosteriorEngine(max_grids=0)


def test_a_planning_step_validates_each_array_once(monkeypatch):
    calls: list[str] = []

    def counting(original):
        def wrapper(name, *args, **kwargs):
            calls.append(name)
            return original(name, *args, **kwargs)

        return wrapper

    check_range = counting(data_module.check_range)
    for module in (data_module, assembly):
        monkeypatch.setattr(module, "check_range", check_range)
    monkeypatch.setattr(data_module, "check_abs", counting(data_module.check_abs))
    engine = GPFusion(PAPER_PRIOR, DEFAULT_GRID_M, mode="safe")
    calls.clear()
    data = assemble_inputs(
        DEFAULT_GRID_M, np.full(51, 0.5), np.full(51, 0.1), local_mu=0.42, mode="safe"
    )
    engine.step(data)
    assert sorted(calls) == sorted(
        ["s_grid_m", "predictive_mu", "predictive_margin where predictive_mu is given",
         "local_mu", "local_margin"]
    )


def test_step_rejects_untyped_data():
    with pytest.raises(ValueError, match="FusionData"):
        GPFusion().step((np.zeros(1), np.zeros(1), np.zeros(1)))


def test_fusion_data_is_read_only_and_leaves_the_caller_array_writable():
    mu = np.array([0.4, 0.5])
    d = FusionData([0.0, 1.0], mu, 0.1)
    with pytest.raises(ValueError):
        d.mu[0] = 1.0
    assert mu.flags.writeable  # the read-only flag is on FusionData's own view
    assert d.groups is None and d.mu_max == 0.5


def test_fuse_returns_the_same_result_through_every_entry_point():
    data = assemble_inputs(DEFAULT_GRID_M, np.full(51, 0.5), np.full(51, 0.1), local_mu=0.42)
    for mode in ("paper", "safe"):
        a = GPFusion(PAPER_PRIOR, DEFAULT_GRID_M, mode=mode).step(data)
        b = fuse(data.s_m, data.mu, data.margin, PAPER_PRIOR, DEFAULT_GRID_M,
                 groups=data.groups, mode=mode)
        np.testing.assert_array_equal(a.mu_hat, b.mu_hat)
        np.testing.assert_array_equal(a.std, b.std)
