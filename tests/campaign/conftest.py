"""Short campaigns (pop-up, about a second of simulated time per run) for the campaign tests."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

SHORT = 'overrides = ["duration_s=1.0"]'


@pytest.fixture
def campaign_file(tmp_path: Path) -> Callable[..., Path]:
    """Write a campaign TOML (``body`` after the short-run overrides) and return its path."""

    def write(body: str, name: str = "campaign.toml", overrides: str = SHORT) -> Path:
        path = tmp_path / name
        path.write_text(f'name = "test"\n{overrides}\n{body}\n')
        return path

    return write

