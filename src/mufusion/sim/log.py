"""One run log: everything a metric or a figure needs, written as CSV + JSON, read back with pandas.

Files in a run directory:

``meta.json``
    scenario configuration, friction configuration, vehicle, road description, obstacles, rates.
``timeseries.csv``
    one row per controller tick: time, plant state (Cartesian and Frenet), actuator commands,
    tire utilisation per axle, true friction per axle, estimator availability, obstacle flags.
``planning_steps.csv``
    one row per planning step: solver status, fallback, sampling re-initialisation, local estimate.
``plans.csv``
    one row per planning step and stage: planned state and tire forces, the force limits used.
``estimates.csv``
    one row per planning step and grid point: true μ, μ̂ and (fused configurations) the posterior
    mean and standard deviation.
``timing.csv``
    wall-clock solve times per planning step. Kept apart because it is the only part of a run that
    is not a deterministic function of the scenario and its seed.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

_TABLES = ("timeseries", "planning_steps", "plans", "estimates", "timing")


@dataclass
class RunLog:
    """Records of one closed-loop run; appended to by the simulator, read by metrics and plots."""

    meta: dict[str, Any] = field(default_factory=dict)
    _rows: dict[str, list[dict[str, Any]]] = field(
        default_factory=lambda: {name: [] for name in _TABLES}
    )
    _block_rows: dict[str, list[pd.DataFrame]] = field(
        default_factory=lambda: {name: [] for name in _TABLES}
    )
    _frames: dict[str, pd.DataFrame] | None = None

    def append(self, table: str, row: dict[str, Any]) -> None:
        """Append one row (a flat mapping of column name to scalar) to ``table``."""
        self._rows[table].append(row)
        self._frames = None

    def append_block(self, table: str, columns: dict[str, Any]) -> None:
        """Append several rows at once, given as equal-length column arrays (or scalars)."""
        self._block_rows[table].append(pd.DataFrame(columns))
        self._frames = None

    def frame(self, table: str) -> pd.DataFrame:
        """The table as a DataFrame (rows in the order they were appended)."""
        if table not in _TABLES:
            raise ValueError(f"table must be one of {list(_TABLES)}, got {table!r}")
        if self._frames is None:
            self._frames = {}
        if table not in self._frames:
            parts = []
            if self._rows[table]:
                parts.append(pd.DataFrame(self._rows[table]))
            parts.extend(self._block_rows[table])
            self._frames[table] = (
                pd.concat(parts, ignore_index=True) if parts else pd.DataFrame()
            )
        return self._frames[table]

    @property
    def timeseries(self) -> pd.DataFrame:
        return self.frame("timeseries")

    @property
    def planning_steps(self) -> pd.DataFrame:
        return self.frame("planning_steps")

    @property
    def plans(self) -> pd.DataFrame:
        return self.frame("plans")

    @property
    def estimates(self) -> pd.DataFrame:
        return self.frame("estimates")

    @property
    def timing(self) -> pd.DataFrame:
        return self.frame("timing")

    def save(self, directory: str | Path) -> Path:
        """Write the log into ``directory`` (created if needed); returns the directory."""
        out = Path(directory)
        out.mkdir(parents=True, exist_ok=True)
        (out / "meta.json").write_text(json.dumps(_jsonable(self.meta), indent=2))
        for table in _TABLES:
            self.frame(table).to_csv(out / f"{table}.csv", index=False, float_format="%.9g")
        return out


def load_run(directory: str | Path) -> RunLog:
    """Read a run log written by :meth:`RunLog.save`.

    Raises
    ------
    ValueError
        If ``directory`` is not a run directory (no ``meta.json``).
    """
    path = Path(directory)
    if not (path / "meta.json").is_file():
        raise ValueError(f"{str(path)!r} is not a mufusion run directory (no meta.json)")
    log = RunLog(meta=json.loads((path / "meta.json").read_text()))
    log._frames = {}
    for table in _TABLES:
        file = path / f"{table}.csv"
        try:
            log._frames[table] = pd.read_csv(file) if file.is_file() else pd.DataFrame()
        except pd.errors.EmptyDataError:
            log._frames[table] = pd.DataFrame()
    return log


def _jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value
