"""The command line's checks of its input, made before the heavy stack loads.

These functions import the schema side of the library only (the scenario and campaign models,
the configuration registry, the output rules): a typo in a scenario or campaign file, a ``--set``
override or an option is refused in well under a second, before acados, CasADi, matplotlib,
pandas or SciPy load (docs/performance.md, "Input errors"). Each raises ``ValueError`` with a
message naming the option or the field and what it allows; the command turns that into exit
code 2.
"""

from __future__ import annotations

import os
import shlex
from dataclasses import dataclass
from pathlib import Path

from mufusion.campaign import (
    ENGINES,
    CampaignFile,
    RunSpec,
    campaign_specs,
    load_campaign,
    prepare_output,
)
from mufusion.campaign.schema import Engine
from mufusion.configurations.plugins import check_plugins
from mufusion.scenarios import ScenarioConfig, load_scenario


def check_out_dir(out: Path, option: str = "--out") -> None:
    """Raise ``ValueError`` if ``out`` cannot be a writable output directory."""
    existing = next((p for p in (out, *out.parents) if p.exists()), None)
    if out.exists() and not out.is_dir():
        raise ValueError(f"{option} {str(out)!r} is a file, not a directory")
    if existing is not None and not existing.is_dir():
        raise ValueError(f"{option} {str(out)!r}: {str(existing)!r} is a file, not a directory")
    if existing is not None and not os.access(existing, os.W_OK | os.X_OK):
        raise ValueError(
            f"{option} {str(out)!r} is not writable ({str(existing)!r} denies writing)"
        )


def check_jobs(jobs: int | None) -> None:
    """Raise ``ValueError`` unless ``jobs`` is None (one per core) or >= 1."""
    if jobs is not None and jobs < 1:
        raise ValueError(f"--jobs must be >= 1, got {jobs}")


def run_input(
    scenario: str,
    config: str,
    overrides: list[str],
    out: Path,
    planner: str | None = None,
    controller: str | None = None,
) -> ScenarioConfig:
    """The validated scenario of ``mufusion run`` (its file or name with the ``--set``
    overrides applied), after checking ``--config``, ``--planner``, ``--controller`` (a plug-in
    named there is imported: :func:`mufusion.configurations.plugins.check_plugins`) and
    ``--out``.

    Raises
    ------
    ValueError
        Naming the option or the scenario field.
    """
    check_plugins(config=config, planner=planner, controller=controller)
    cfg = load_scenario(scenario, overrides)
    check_out_dir(out)
    return cfg


@dataclass(frozen=True)
class CampaignInput:
    """A checked ``mufusion campaign`` invocation: the campaign, this shard's runs, the engine.

    Attributes
    ----------
    plan
        The campaign file.
    specs
        The runs of shard ``shard`` of ``shards``.
    shard, shards
        ``--shard K/N``.
    engine
        ``--engine``.
    """

    plan: CampaignFile
    specs: list[RunSpec]
    shard: int
    shards: int
    engine: Engine


def campaign_input(
    file: Path,
    out: Path,
    *,
    jobs: int | None,
    shard: str,
    engine: str,
    address: str | None,
    resume: bool,
    overwrite: bool,
) -> CampaignInput:
    """Check a ``mufusion campaign`` invocation and prepare its output directory.

    The campaign file and every run's scenario are read and validated, then ``out`` is made
    ready (:func:`mufusion.campaign.prepare_output`: cleared with ``overwrite``, checked to hold
    the same campaign with ``resume``) and the campaign recorded in it.

    Raises
    ------
    ValueError
        Naming the option (``--jobs``, ``--engine``, ``--address``, ``--shard``, ``--out``) or
        the campaign file's key.
    """
    check_jobs(jobs)
    if engine not in ENGINES:
        raise ValueError(f"--engine must be one of {', '.join(ENGINES)}, got {engine!r}")
    if address is not None and engine != "ray":
        raise ValueError("--address needs --engine ray")
    parts = shard.split("/")
    if len(parts) != 2 or not all(p.strip().isdigit() for p in parts):
        raise ValueError(f"--shard must be K/N with 0 <= K < N, got {shard!r}")
    k, n = int(parts[0]), int(parts[1])
    plan = load_campaign(file)
    specs = campaign_specs(plan, shard=k, shards=n)
    manifest = {"campaign": plan.model_dump(mode="json"), "shard": f"{k}/{n}"}
    prepare_output(out, manifest, overwrite=overwrite, resume=resume)
    return CampaignInput(plan, specs, k, n, "ray" if engine == "ray" else "pool")


def resume_command(
    file: Path, out: Path, *, shard: str, engine: str, address: str | None, jobs: int | None
) -> str:
    """The ``mufusion campaign`` command line that resumes an interrupted campaign (the options
    that identify it; defaults left out), quoted for a POSIX shell.

    Examples
    --------
    >>> resume_command(Path("c.toml"), Path("my out"), shard="0/1", engine="ray", address=None,
    ...                jobs=2)
    "mufusion campaign c.toml --out 'my out' --resume --engine ray --jobs 2"
    """
    again = ["mufusion", "campaign", str(file), "--out", str(out), "--resume"]
    again += [] if shard == "0/1" else ["--shard", shard]
    again += [] if engine == "pool" else ["--engine", engine]
    again += [] if address is None else ["--address", address]
    again += [] if jobs is None else ["--jobs", str(jobs)]
    return shlex.join(again)
