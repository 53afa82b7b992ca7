"""One run log: typed records in, pandas tables out, CSV + JSON on disk.

The tables and their columns are the record types of :mod:`mufusion.sim.records`; a saved run is
checked against them when it is loaded, so a reader never meets a missing or renamed column.

Files in a run directory: one ``<table>.csv`` per record type, ``solver_messages.txt`` (what the
solver library printed during the run, one message a line: :mod:`mufusion.sim.solver_output`) and
``meta.json`` (:class:`~mufusion.sim.records.RunMeta`, plus ``"files"``: each other file's row
count and SHA-256). ``meta.json`` is written last, so it vouches for the others: a file that a
crash truncated or a hand altered is refused on load, naming it. A run saved before the stamps
existed (no ``"files"``) loads unchecked.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import tempfile
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from pydantic import BaseModel, ConfigDict

from mufusion.sim.records import (
    RECORD_TYPES,
    EstimateGrid,
    Event,
    PlanningStep,
    PlanStages,
    RecoveryCandidate,
    RunMeta,
    StepTiming,
    Tick,
    columns,
)

TABLES: tuple[str, ...] = tuple(RECORD_TYPES)

Record = Tick | PlanningStep | StepTiming | Event | RecoveryCandidate | PlanStages | EstimateGrid

SOLVER_MESSAGES_FILE = "solver_messages.txt"
STAMPS_KEY = "files"
"""The key of ``meta.json`` that holds each other file's :class:`FileStamp`, by file name."""


class FileStamp(BaseModel):
    """What ``meta.json`` records of one file of the run: its rows (a table's data rows, a text
    file's lines) and its SHA-256 (hex)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    rows: int
    sha256: str


def _stamp(data: bytes, rows: int) -> FileStamp:
    return FileStamp(rows=rows, sha256=hashlib.sha256(data).hexdigest())


class RunLog:
    """Records of one closed-loop run; appended to by the recorder, read by metrics and plots.

    Parameters
    ----------
    meta
        The run's metadata.

    Attributes
    ----------
    solver_messages
        What the solver library printed during the run, one message each (the runner fills it;
        :mod:`mufusion.sim.solver_output`).
    """

    def __init__(self, meta: RunMeta) -> None:
        self.meta = meta
        self.solver_messages: list[str] = []
        self._records: dict[str, list[Any]] = {name: [] for name in TABLES}
        self._frames: dict[str, pd.DataFrame] = {}

    def append(self, record: Record) -> None:
        """Append one record (a row, or a block of rows) to its table."""
        self._records[record.table].append(record)
        self._frames.pop(record.table, None)

    def extend(self, records: Iterable[Record]) -> None:
        """Append several records."""
        for record in records:
            self.append(record)

    def frame(self, table: str) -> pd.DataFrame:
        """The table as a DataFrame with the record type's columns, rows in append order.

        Raises
        ------
        ValueError
            If ``table`` is not one of :data:`TABLES`.
        """
        if table not in RECORD_TYPES:
            raise ValueError(f"table must be one of {list(TABLES)}, got {table!r}")
        if table not in self._frames:
            self._frames[table] = _to_frame(RECORD_TYPES[table], self._records[table])
        return self._frames[table]

    @property
    def timeseries(self) -> pd.DataFrame:
        return self.frame(Tick.table)

    @property
    def planning_steps(self) -> pd.DataFrame:
        return self.frame(PlanningStep.table)

    @property
    def plans(self) -> pd.DataFrame:
        return self.frame(PlanStages.table)

    @property
    def estimates(self) -> pd.DataFrame:
        return self.frame(EstimateGrid.table)

    @property
    def timing(self) -> pd.DataFrame:
        return self.frame(StepTiming.table)

    @property
    def events(self) -> pd.DataFrame:
        return self.frame(Event.table)

    def save(self, directory: str | Path) -> Path:
        """Write the log into ``directory`` (created if needed); returns the directory.

        Each file is written under a temporary name and renamed, so a reader (or an interrupted
        campaign) never sees a half-written file; ``meta.json`` comes last, with each other
        file's row count and checksum.
        """
        out = Path(directory)
        out.mkdir(parents=True, exist_ok=True)
        texts = {}
        for table in TABLES:
            frame = self.frame(table)
            texts[f"{table}.csv"] = (frame.to_csv(index=False, float_format="%.9g"), len(frame))
        messages = self.solver_messages
        texts[SOLVER_MESSAGES_FILE] = ("".join(f"{m}\n" for m in messages), len(messages))
        stamps = {}
        for name, (text, rows) in texts.items():
            _write_atomic(out / name, text)
            stamps[name] = _stamp(text.encode("utf-8"), rows).model_dump()
        # Last: meta.json vouches for the files written before it.
        meta = json.loads(self.meta.model_dump_json())
        _write_atomic(out / "meta.json", json.dumps({**meta, STAMPS_KEY: stamps}, indent=1))
        return out


def _to_frame(record_type: type, records: list[Any]) -> pd.DataFrame:
    names = columns(record_type)
    if not records:
        return pd.DataFrame({name: pd.Series(dtype=float) for name in names})
    if record_type in _BLOCKS:
        # Blocks: one concatenation per column (scalars repeat over the block's rows).
        sizes = [len(r.k if isinstance(r, PlanStages) else r.s_ahead_m) for r in records]
        pairs = list(zip(records, sizes, strict=True))
        data = {
            name: np.concatenate([np.broadcast_to(getattr(r, name), (n,)) for r, n in pairs])
            for name in names
        }
        return pd.DataFrame(data, columns=list(names))
    return pd.DataFrame.from_records([tuple(vars(r).values()) for r in records], columns=names)


_BLOCKS = (PlanStages, EstimateGrid)


def _write_atomic(path: Path, text: str) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def load_run(directory: str | Path) -> RunLog:
    """Read a run log written by :meth:`RunLog.save`.

    Raises
    ------
    ValueError
        If ``directory`` is not a run directory (no ``meta.json``), the metadata does not match
        :class:`~mufusion.sim.records.RunMeta`, a file of the run is missing, truncated or
        altered (its row count or checksum differs from ``meta.json``'s), or a table lacks one
        of its record's columns (the message names the file).
    """
    path = Path(directory)
    meta_file = path / "meta.json"
    if not meta_file.is_file():
        raise ValueError(f"{str(path)!r} is not a mufusion run directory (no meta.json)")
    try:
        raw = json.loads(meta_file.read_text(encoding="utf-8"))
        stamps = raw.pop(STAMPS_KEY, None) if isinstance(raw, dict) else None
        meta = RunMeta.model_validate_json(json.dumps(raw))
        checked = {f: FileStamp.model_validate(v) for f, v in (stamps or {}).items()}
    except (ValueError, AttributeError) as err:
        raise ValueError(f"{str(meta_file)!r} is not a valid run metadata file: {err}") from None
    log = RunLog(meta)
    for table, record_type in RECORD_TYPES.items():
        file = path / f"{table}.csv"
        frame = _read_table(file)
        if file.name in checked:
            _check_stamp(file, 0 if frame is None else len(frame), checked[file.name])
        if frame is None:
            frame = _to_frame(record_type, [])
        # A column added to a record later, with a default, reads as that default in a log
        # written before it existed.
        for f in dataclasses.fields(record_type):
            if f.name not in frame.columns and f.default is not dataclasses.MISSING:
                frame[f.name] = f.default
        missing = [c for c in columns(record_type) if c not in frame.columns]
        if missing:
            raise ValueError(f"{str(file)!r} lacks the columns {missing} of table {table!r}")
        log._frames[table] = frame
    messages = path / SOLVER_MESSAGES_FILE
    if messages.is_file():
        log.solver_messages = messages.read_text(encoding="utf-8").splitlines()
    if messages.name in checked:
        _check_stamp(messages, len(log.solver_messages), checked[messages.name])
    return log


def _check_stamp(file: Path, rows: int, stamp: FileStamp) -> None:
    """Raise ``ValueError`` naming ``file`` if it is not the file ``meta.json`` vouches for."""
    if not file.is_file():
        raise ValueError(f"{str(file)!r} is missing: its run's meta.json records "
                         f"{stamp.rows} rows")
    if rows != stamp.rows:
        raise ValueError(f"{str(file)!r} has {rows} rows, its run's meta.json records "
                         f"{stamp.rows}: the file was truncated or altered")
    if _stamp(file.read_bytes(), rows).sha256 != stamp.sha256:
        raise ValueError(f"{str(file)!r} does not match the checksum in its run's meta.json "
                         "(SHA-256): the file was altered")


def _read_table(file: Path) -> pd.DataFrame | None:
    if not file.is_file():
        return None
    try:
        return pd.read_csv(file)
    except pd.errors.EmptyDataError:
        return None


def finite_or_nan(value: float | None) -> float:
    """``value`` as a float, NaN for None or a non-finite value (for optional columns)."""
    return math.nan if value is None or not math.isfinite(value) else float(value)
