"""Campaign outputs on disk: atomic writes, the output directory's rules, completed runs.

A file or run directory is written under a temporary name in the same directory and renamed into
place, so a reader (or a resumed campaign) sees either nothing or the complete thing, never half
of it, whatever interrupts the writer. A run directory is complete when it exists under its final
name: its ``result.json`` is the last file written before the rename.
"""

from __future__ import annotations

import json
import os
import shutil
import uuid
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

RESULT_FILE = "result.json"
MANIFEST_FILE = "campaign.json"
RUNS_DIR = "runs"
# Temporary names start with this, so that clean-up never touches anything else.
_TMP_PREFIX = ".tmp-"


def _tmp_sibling(path: Path) -> Path:
    return path.with_name(f"{_TMP_PREFIX}{path.name}-{os.getpid()}-{uuid.uuid4().hex[:8]}")


def atomic_write(path: Path, write: Callable[[Path], object]) -> Path:
    """Call ``write(tmp)`` to write a file under a temporary name, then rename it to ``path``.

    Parameters
    ----------
    path
        Final file name; its directory must exist.
    write
        Writes the complete file to the path it is given (e.g. ``df.to_parquet``).

    Returns
    -------
    Path
        ``path``.
    """
    tmp = _tmp_sibling(path)
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
    return path


def atomic_write_text(path: Path, text: str) -> Path:
    """Write ``text`` to ``path`` atomically (temporary name, then rename)."""
    return atomic_write(path, lambda tmp: tmp.write_text(text))


def publish_run(
    directory: Path, files: Mapping[str, bytes], result: Mapping[str, Any]
) -> Path:
    """Write a run's files and its ``result.json`` into ``directory`` atomically.

    The files go into a temporary sibling directory, ``result.json`` last, which is then renamed
    to ``directory``; a previous directory of that name is replaced.

    Returns
    -------
    Path
        ``directory``.
    """
    tmp = _tmp_sibling(directory)
    tmp.mkdir(parents=True)
    try:
        for name, data in files.items():
            (tmp / name).write_bytes(data)
        (tmp / RESULT_FILE).write_text(json.dumps(result, indent=2))
        if directory.exists():
            old = _tmp_sibling(directory)
            directory.rename(old)
            tmp.rename(directory)
            shutil.rmtree(old)
        else:
            tmp.rename(directory)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp)
    return directory


def read_result(directory: Path) -> dict[str, Any] | None:
    """The ``result.json`` of a complete run directory, ``None`` if there is none."""
    file = directory / RESULT_FILE
    if not file.is_file():
        return None
    try:
        data = json.loads(file.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError):
        return None
    return data if isinstance(data, dict) else None


def remove_temporaries(directory: Path) -> None:
    """Delete what interrupted writers left in ``directory`` (temporary names only)."""
    if not directory.is_dir():
        return
    for entry in directory.iterdir():
        if entry.name.startswith(_TMP_PREFIX):
            if entry.is_dir():
                shutil.rmtree(entry, ignore_errors=True)
            else:
                entry.unlink(missing_ok=True)


def prepare_output(
    out: Path, manifest: Mapping[str, Any], *, overwrite: bool = False, resume: bool = False
) -> None:
    """Make ``out`` ready for a campaign and record the campaign in ``out/campaign.json``.

    An empty or missing ``out`` is used as it is. A non-empty one is refused unless
    ``overwrite`` (its contents are deleted first; only a directory that holds a campaign, i.e.
    a ``campaign.json``, is ever cleared) or ``resume`` (it must hold the same campaign).

    Parameters
    ----------
    out
        Output directory.
    manifest
        What identifies the campaign (its file's contents, the shard); stored as JSON.
    overwrite, resume
        At most one of them.

    Raises
    ------
    ValueError
        If ``out`` is a file or cannot be created or written, both flags are set, or ``out`` is
        non-empty and the flags do not allow writing into it.
    """
    if overwrite and resume:
        raise ValueError("--overwrite and --resume exclude each other; pick one")
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out {str(out)!r} is a file, not a directory")
    manifest_text = json.dumps(manifest, indent=2, sort_keys=True)
    entries = list(out.iterdir()) if out.is_dir() else []
    stored = out / MANIFEST_FILE
    if entries and not (overwrite or resume):
        raise ValueError(
            f"--out {str(out)!r} is not empty; pass --overwrite to clear it first or --resume "
            "to continue the campaign in it"
        )
    if entries and overwrite:
        if not stored.is_file():
            raise ValueError(
                f"refusing to clear --out {str(out)!r}: it holds no campaign (no {MANIFEST_FILE}); "
                "choose another directory or empty it yourself"
            )
        for entry in entries:
            if entry.is_dir() and not entry.is_symlink():
                shutil.rmtree(entry)
            else:
                entry.unlink()
    if entries and resume and not overwrite:
        if not stored.is_file() or stored.read_text() != manifest_text:
            raise ValueError(
                f"cannot resume in --out {str(out)!r}: it holds a different campaign or shard "
                f"(its {MANIFEST_FILE} differs); use another directory or --overwrite"
            )
    try:
        (out / RUNS_DIR).mkdir(parents=True, exist_ok=True)
        remove_temporaries(out)
        remove_temporaries(out / RUNS_DIR)
        atomic_write_text(stored, manifest_text)
    except OSError as err:
        raise ValueError(f"--out {str(out)!r} is not writable: {err}") from None
