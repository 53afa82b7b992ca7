"""Campaigns: many scenario variants × friction configurations × seeds, run on a process pool or
on Ray, stored atomically and resumably, summarised as one tidy table and as Monte Carlo rates.

Modules, in data-flow order: :mod:`~mufusion.campaign.schema` (the campaign file),
:mod:`~mufusion.campaign.specs` (runs and their names), :mod:`~mufusion.campaign.engines`
(where runs execute), :mod:`~mufusion.campaign.storage` (atomic writes, ``--out`` rules),
:mod:`~mufusion.campaign.runs` (running a campaign), :mod:`~mufusion.campaign.results`
(summary and table), :mod:`~mufusion.campaign.stats` (rates, intervals, distributions),
:mod:`~mufusion.campaign.report` (the Markdown/HTML page).
"""

from typing import TYPE_CHECKING

from mufusion._lazy import lazy_getattr
from mufusion.campaign.schema import ENGINES, CampaignFile, load_campaign
from mufusion.campaign.specs import (
    RunSpec,
    campaign_specs,
    check_distinct,
    with_indices,
)
from mufusion.campaign.storage import prepare_output

if TYPE_CHECKING:
    from mufusion.campaign.engines import execute_run, warm_up_solvers
    from mufusion.campaign.results import RunResult, write_results
    from mufusion.campaign.runs import CampaignInterrupted, execute_campaign, run_campaign
    from mufusion.campaign.stats import graded_summary, outcome_rates, wilson_interval

__all__ = [
    "ENGINES",
    "CampaignFile",
    "CampaignInterrupted",
    "RunResult",
    "RunSpec",
    "campaign_specs",
    "check_distinct",
    "execute_campaign",
    "execute_run",
    "graded_summary",
    "load_campaign",
    "outcome_rates",
    "prepare_output",
    "run_campaign",
    "warm_up_solvers",
    "wilson_interval",
    "with_indices",
    "write_results",
]

# The engines, results and statistics (the closed loop, pandas and SciPy with them) load on first
# use: the command line reads and checks a campaign file and its output directory first.
__getattr__ = lazy_getattr(__name__, {
    "execute_run": "engines", "warm_up_solvers": "engines",
    "RunResult": "results", "write_results": "results",
    "CampaignInterrupted": "runs", "execute_campaign": "runs", "run_campaign": "runs",
    "graded_summary": "stats", "outcome_rates": "stats", "wilson_interval": "stats",
})
