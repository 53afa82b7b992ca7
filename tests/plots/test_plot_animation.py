"""The run animation: a GIF with a bounded number of frames."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from mufusion.plots import animate_run
from mufusion.plots.animation import MAX_FRAMES, frame_rows


def test_animation_writes_a_gif_with_bounded_frames(saved_log, tmp_path: Path) -> None:
    log = saved_log("popup", "P", duration_s=0.6, collision_at_s=5.0)
    out = animate_run(log, tmp_path / "run.gif", fps=5)
    assert out.read_bytes()[:6] in (b"GIF87a", b"GIF89a")
    with Image.open(out) as gif:
        assert gif.n_frames == min(len(log.timeseries), MAX_FRAMES)


@pytest.mark.parametrize("n_rows", [1, 7, 60, 61, 1001])
def test_frame_rows_spread_over_the_run(n_rows: int) -> None:
    rows = frame_rows(n_rows)
    assert rows[0] == 0 and rows[-1] == n_rows - 1
    assert len(rows) == min(n_rows, MAX_FRAMES)
    assert np.all(np.diff(rows) > 0)


def test_animation_rejects_bad_fps(saved_log, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="fps must be an integer"):
        animate_run(saved_log("turn", "F", duration_s=0.5), tmp_path / "x.gif", fps=0)
