"""The stand-alone fusion demonstration figure (cf. the paper's Fig. 2)."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.fusion import LOCAL_GROUP
from mufusion.plots.fusion_demo import (
    build_fusion_demo_figure,
    demo_estimates,
    fusion_demo_figure,
)

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("mode", ["paper", "safe", "both"])
def test_writes_a_png(tmp_path, mode):
    out = fusion_demo_figure(tmp_path / "sub" / f"demo_{mode}.png", mode=mode)
    assert out.exists() and out.stat().st_size > 10_000
    assert out.read_bytes()[:8] == PNG_MAGIC


def test_panels_labels_and_legend_outside_the_axes():
    fig = build_fusion_demo_figure("both")
    axes = fig.get_axes()
    assert len(axes) == 2
    assert [ax.get_title() for ax in axes] == ["F (paper fusion)", "F-safe (safe fusion)"]
    assert all(ax.get_xlabel() == "distance ahead s [m]" for ax in axes)
    assert axes[0].get_ylabel() == "friction coefficient μ [-]"
    assert not any(ax.get_legend() for ax in axes)  # one figure legend, below the panels
    (legend,) = fig.legends
    labels = {t.get_text() for t in legend.get_texts()}
    assert {"true μ", "local estimate ± margin", "camera estimate ± margin",
            "posterior 95 % band", "prior 95 % band"} <= labels
    gids = {artist.get_gid() for ax in axes for artist in ax.get_children()}
    assert {"mu_hat", "true", "posterior_mean", "posterior_band", "prior"} <= gids


def test_demo_data_has_local_and_camera_points_and_the_low_mu_section():
    ((mu_true, est),) = demo_estimates(modes=("paper",)).values()
    assert est.local_available
    local = est.data.groups == LOCAL_GROUP
    assert local.any() and (~local).any()
    assert mu_true[0] == 0.8 and mu_true[-1] == 0.3
    # Approaching the low-μ section, the fused estimate drops well below the dry value.
    assert est.mu_hat[40] < 0.3 < est.mu_hat[0]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"mode": "both-ish"}, r"mode must be one of \['paper', 'safe', 'both'\]"),
        ({"s_max_m": -1.0}, "s_max_m must be finite and > 0"),
        ({"ds_m": 0.0}, "ds_m must be in"),
        ({"mu_after": 0.05}, "mu must lie in a surface class"),
    ],
)
def test_rejects_bad_arguments(tmp_path, kwargs, match):
    out = tmp_path / "bad.png"
    with pytest.raises(ValueError, match=match):
        fusion_demo_figure(out, **kwargs)
    assert not out.exists()


def test_random_errors_follow_the_seed():
    a = demo_estimates(modes=("paper",), predictive_error="random", seed=3)["paper"][1]
    b = demo_estimates(modes=("paper",), predictive_error="random", seed=3)["paper"][1]
    np.testing.assert_array_equal(a.mu_hat, b.mu_hat)
