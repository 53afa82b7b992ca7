"""Same seeds, same results, whichever engine runs them: the process pool and a local Ray."""

from __future__ import annotations

import pytest

from mufusion.campaign import (
    CampaignInterrupted,
    campaign_specs,
    execute_campaign,
    load_campaign,
)
from mufusion.campaign.engines import dispatch
from mufusion.campaign.stats import WALL_CLOCK_SUFFIX

CAMPAIGN = """
scenarios = ["popup"]
configs = ["F"]
seeds = 3
overrides = ["duration_s=1.5", "estimation.local_error=random",
             "estimation.predictive_error=random"]
"""


def _deterministic(metrics) -> dict:
    return {k: v for k, v in metrics.to_dict().items() if not k.endswith(WALL_CLOCK_SUFFIX)}


def _log_files(directory) -> dict[str, bytes]:
    # timing.csv holds wall-clock times, the one part of a log that is not deterministic;
    # result.json holds the metrics, compared above without the timings.
    skip = {"timing.csv", "result.json"}
    return {p.name: p.read_bytes() for p in directory.iterdir() if p.name not in skip}


@pytest.mark.slow
def test_pool_and_local_ray_give_identical_runs_for_the_same_seeds(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text(CAMPAIGN)
    specs = campaign_specs(load_campaign(path))
    pool = execute_campaign(specs, tmp_path / "pool", engine="pool", jobs=2)
    ray = execute_campaign(specs, tmp_path / "ray", engine="ray", jobs=2)
    assert [r.error for r in pool + ray] == [None] * 6
    for a, b in zip(pool, ray, strict=True):
        assert a.spec == b.spec and a.seed == b.seed
        assert _deterministic(a.metrics) == _deterministic(b.metrics)
        assert _log_files(a.directory) == _log_files(b.directory)
    # The seeds reach the random error models: different seeds, different estimates.
    estimates = {r.seed: (r.directory / "estimates.csv").read_bytes() for r in pool}
    assert len(set(estimates.values())) == 3


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"engine": "dask"}, "engine must be one of"),
        ({"jobs": 0}, "jobs must be >= 1"),
        ({"address": "10.0.0.1:6379"}, "address is only used by the ray engine"),
    ],
)
def test_dispatch_rejects_bad_options(kwargs, match):
    with pytest.raises(ValueError, match=match):
        dispatch([], print, **kwargs)


@pytest.mark.slow
def test_ctrl_c_cancels_the_ray_tasks_and_shuts_the_local_instance_down(tmp_path):
    import ray

    path = tmp_path / "c.toml"
    path.write_text(CAMPAIGN.replace("seeds = 3", "seeds = 6"))
    specs = campaign_specs(load_campaign(path))

    def interrupt(_spec):
        raise KeyboardInterrupt

    with pytest.raises(CampaignInterrupted) as stop:
        execute_campaign(specs, tmp_path / "runs", engine="ray", jobs=2, on_done=interrupt)
    assert len(stop.value.finished) == 1 and len(stop.value.pending) == 5
    assert not ray.is_initialized()
    assert [p.name for p in (tmp_path / "runs").iterdir()] == [stop.value.finished[0].spec.name]
