"""Fusion speed on the paper's 51-point problem, against scikit-learn in the same run.

The problem: grid 0, 1, …, 50 m; the local estimate (0.425 ± 0.025) at s < 5 m, the wet class
(0.5 ± 0.1) elsewhere. Each call is timed alone; the medians are reported. Also the batched form on
1000 horizons with different class changes, in both modes.

With shared reports (issue 40): safe mode with 25 and 250 reports (a fifth of them 0.2 too high,
ages up to 60 s), the best consistent report (decision 0063, the default) against the segment's
lowest report (decision 0060), the rule a user would otherwise pick.

Run: ``python benchmarks/fusion.py``. Prints a table and a final JSON line; numbers go to
docs/performance.md, section "## Fusion".
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import sys
import time

import numpy as np
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, ConstantKernel

from mufusion.estimators.shared import FrictionReport, SharedSettings
from mufusion.fusion import (
    DEFAULT_GRID_M,
    PAPER_PRIOR,
    GPFusion,
    assemble_inputs,
    fuse,
    fuse_batch,
    report_data,
)

N_OURS = 2000
N_SHARED = 200
REPORT_COUNTS = (25, 250)
N_SKLEARN = 200
N_BATCH = 1000
BATCH_REPEATS = 5


def _median_us(fn, n: int) -> float:
    fn()  # warm-up: fills the kernel/feature caches, as in the closed loop after the first step
    times = []
    for _ in range(n):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times) * 1e6


def _sklearn_fuse(s, mu, margin, s_eval):
    kernel = ConstantKernel(PAPER_PRIOR.variance, "fixed") * RBF(
        PAPER_PRIOR.length_scale_m, "fixed"
    )
    gpr = GaussianProcessRegressor(kernel=kernel, alpha=(margin / 1.96) ** 2, optimizer=None)
    gpr.fit(s.reshape(-1, 1), mu - PAPER_PRIOR.mean)
    mean, std = gpr.predict(s_eval.reshape(-1, 1), return_std=True)
    return mean + PAPER_PRIOR.mean, std


def _batch_inputs(rng: np.random.Generator, mode: str = "paper"):
    mu = np.empty((N_BATCH, DEFAULT_GRID_M.size))
    margin = np.empty_like(mu)
    groups = np.empty(mu.shape, dtype=np.int64)
    for b in range(N_BATCH):
        change = rng.uniform(0.0, 50.0)
        first, second = rng.choice([0.8, 0.5, 0.25], 2)
        value = np.where(DEFAULT_GRID_M < change, first, second)
        mar = np.select([value == 0.8, value == 0.5], [0.2, 0.1], 0.15)
        d = assemble_inputs(
            DEFAULT_GRID_M, value, mar, local_mu=rng.uniform(0.2, 0.9), mode=mode
        )
        mu[b], margin[b], groups[b] = d.mu, d.margin, d.groups
    return mu, margin, groups


def _batch_us(grid, mu, margin, groups, mode: str) -> float:
    fuse_batch(grid, mu, margin, PAPER_PRIOR, grid, groups=groups, mode=mode)
    times = []
    for _ in range(BATCH_REPEATS):
        start = time.perf_counter()
        fuse_batch(grid, mu, margin, PAPER_PRIOR, grid, groups=groups, mode=mode)
        times.append(time.perf_counter() - start)
    return statistics.median(times) / N_BATCH * 1e6


def _shared_us(grid, data, n_reports: int, rule: str) -> float:
    rng = np.random.default_rng(n_reports)
    reports = [
        FrictionReport.numeric(
            float(rng.uniform(0.0, 50.0)), 0.5 + (0.2 if i % 5 == 0 else 0.0), 0.025,
            t_created_s=-float(rng.uniform(0.0, 60.0)), position_std_m=0.5,
            sender=f"v{i % max(2, n_reports // 5)}",
        )
        for i in range(n_reports)
    ]
    rd = report_data(reports, t_now_s=0.0, s_ego_m=0.0, prior=PAPER_PRIOR,
                     settings=SharedSettings(report_bound=rule))  # type: ignore[arg-type]
    return _median_us(
        lambda: fuse(data.s_m, data.mu, data.margin, PAPER_PRIOR, grid, groups=data.groups,
                     mode="safe", reports=rd),
        N_SHARED,
    )


def main() -> None:
    grid = DEFAULT_GRID_M
    data = assemble_inputs(grid, np.full(grid.size, 0.5), np.full(grid.size, 0.1), local_mu=0.425)
    s, mu, margin, groups = data.s_m, data.mu, data.margin, data.groups

    ours = fuse(s, mu, margin, PAPER_PRIOR, grid)
    ref_mean, ref_std = _sklearn_fuse(s, mu, margin, grid)
    max_diff = float(max(np.abs(ours.mean - ref_mean).max(), np.abs(ours.std - ref_std).max()))

    t_paper = _median_us(lambda: fuse(s, mu, margin, PAPER_PRIOR, grid), N_OURS)
    t_safe = _median_us(
        lambda: fuse(s, mu, margin, PAPER_PRIOR, grid, groups=groups, mode="safe"), N_OURS
    )
    engine = GPFusion(PAPER_PRIOR, grid)
    t_engine = _median_us(lambda: engine.step(data), N_OURS)
    t_sklearn = _median_us(lambda: _sklearn_fuse(s, mu, margin, grid), N_SKLEARN)

    t_batch = _batch_us(grid, *_batch_inputs(np.random.default_rng(0)), "paper")
    t_batch_safe = _batch_us(grid, *_batch_inputs(np.random.default_rng(0), "safe"), "safe")

    safe_data = assemble_inputs(grid, np.full(grid.size, 0.5), np.full(grid.size, 0.1),
                                local_mu=0.425, mode="safe")
    shared = {(n, rule): _shared_us(grid, safe_data, n, rule)
              for n in REPORT_COUNTS for rule in ("consistent", "lowest")}

    rows = [
        ("fuse, paper mode", t_paper),
        ("fuse, safe mode", t_safe),
        ("GPFusion.step (paper, FusionData)", t_engine),
        ("scikit-learn GaussianProcessRegressor fit+predict", t_sklearn),
        (f"fuse_batch, paper, per horizon ({N_BATCH} horizons)", t_batch),
        (f"fuse_batch, safe, per horizon ({N_BATCH} horizons)", t_batch_safe),
    ] + [
        (f"fuse, safe, {n} reports, {rule}", shared[(n, rule)])
        for n in REPORT_COUNTS for rule in ("consistent", "lowest")
    ]
    print(
        f"machine: nproc={os.cpu_count()}, python {platform.python_version()}, "
        f"numpy {np.__version__}, {platform.machine()}"
    )
    print(f"max |ours - scikit-learn| (mean, std): {max_diff:.1e}")
    print(f"{'case':<56} {'median µs':>10}")
    for name, value in rows:
        print(f"{name:<56} {value:>10.1f}")
    print(f"speed-up vs scikit-learn (paper mode): {t_sklearn / t_paper:.0f}x")
    for n in REPORT_COUNTS:
        ratio = shared[(n, "consistent")] / shared[(n, "lowest")]
        print(f"{n} reports: consistent / lowest = {ratio:.2f}")
    result = {
        "median_fuse_us": round(t_paper, 2),
        "median_fuse_safe_us": round(t_safe, 2),
        "median_gpfusion_step_us": round(t_engine, 2),
        "median_sklearn_us": round(t_sklearn, 2),
        "speedup_vs_sklearn": round(t_sklearn / t_paper, 1),
        "batched_us_per_horizon": round(t_batch, 2),
        "batched_safe_us_per_horizon": round(t_batch_safe, 2),
        "max_abs_diff_vs_sklearn": max_diff,
        **{f"median_safe_{n}_reports_{rule}_us": round(v, 1) for (n, rule), v in shared.items()},
    }
    sys.stdout.write(json.dumps(result) + "\n")


if __name__ == "__main__":
    main()
