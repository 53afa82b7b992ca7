"""Surface-class table and classification (paper Sec. IV-B, configurations P and F)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.estimators import (
    AUTHORS_CLASSES,
    CLASS_TABLES,
    PAPER_CLASSES,
    SurfaceClass,
    class_table,
    classify,
    predictive_estimate,
    validate_classes,
)

mu_in_table = st.floats(min_value=0.1, max_value=1.5, allow_nan=False)


def test_paper_table_values():
    by_name = {c.name: c for c in PAPER_CLASSES}
    assert (by_name["dry"].value, by_name["dry"].margin, by_name["dry"].mu_low) == (0.8, 0.2, 0.6)
    assert (by_name["wet"].value, by_name["wet"].margin, by_name["wet"].mu_low) == (0.5, 0.1, 0.4)
    snow = by_name["snow/ice"]
    assert (snow.value, snow.margin, snow.mu_low, snow.mu_high) == (0.25, 0.15, 0.1, 0.4)


@pytest.mark.parametrize(
    ("mu", "name"),
    [
        (0.1, "snow/ice"),
        (0.3999, "snow/ice"),
        (0.4, "wet"),
        (0.5999, "wet"),
        # The paper leaves μ = 0.6 in no class; half-open [low, high) everywhere puts it in dry.
        (0.6, "dry"),
        (0.89, "dry"),
        (1.0, "dry"),
        (1.5, "dry"),
    ],
)
def test_classify_paper_boundaries(mu, name):
    (index,) = classify([mu])
    assert PAPER_CLASSES[index].name == name


def test_classify_keeps_shape_and_dtype():
    mu = np.array([[0.2, 0.5], [0.8, 1.0]])
    out = classify(mu)
    assert out.shape == (2, 2)
    assert out.dtype.kind == "i"
    assert out.tolist() == [[0, 1], [2, 2]]


@pytest.mark.parametrize("bad", [0.05, 0.0999, -0.3, float("nan")])
def test_classify_outside_every_class_names_mu_and_range(bad):
    with pytest.raises(ValueError, match=r"mu must lie in a surface class.*\[0\.1, inf\]"):
        classify([0.5, bad])


@settings(max_examples=200, deadline=None)
@given(a=mu_in_table, b=mu_in_table)
def test_classify_is_monotone(a, b):
    lo, hi = sorted((a, b))
    assert classify(lo) <= classify(hi)


@settings(max_examples=200, deadline=None)
@given(mu=mu_in_table)
def test_class_contains_mu_and_conservative_value_below(mu):
    c = PAPER_CLASSES[int(classify(mu))]
    assert c.mu_low <= mu < c.mu_high
    # P's value never over-estimates; F's input interval contains μ up to the prior's 1.0.
    assert c.mu_low <= mu
    if mu <= 1.0:
        assert c.value - c.margin - 1e-12 <= mu <= c.value + c.margin + 1e-12


def test_user_table_with_finite_top_is_closed_at_the_top():
    table = (
        SurfaceClass("low", 0.1, 0.5, 0.3, 0.2),
        SurfaceClass("high", 0.5, 1.0, 0.75, 0.25),
    )
    assert classify([0.5, 1.0], table).tolist() == [1, 1]
    with pytest.raises(ValueError, match=r"covered range \[0\.1, 1\.0\]"):
        classify([1.01], table)


def test_user_table_gap_is_unclassifiable():
    table = (SurfaceClass("a", 0.1, 0.3, 0.2, 0.1), SurfaceClass("b", 0.5, 0.9, 0.7, 0.2))
    assert classify([0.2, 0.6], table).tolist() == [0, 1]
    with pytest.raises(ValueError, match="mu must lie in a surface class"):
        classify([0.4], table)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(mu_low=-0.1, mu_high=0.4, value=0.2, margin=0.3), "0 ≤ mu_low < mu_high"),
        (dict(mu_low=0.5, mu_high=0.4, value=0.45, margin=0.1), "0 ≤ mu_low < mu_high"),
        (dict(mu_low=0.4, mu_high=0.6, value=0.7, margin=0.3), "value must lie in"),
        (dict(mu_low=0.4, mu_high=0.6, value=0.5, margin=0.0), "margin must be > 0"),
        (dict(mu_low=0.4, mu_high=0.6, value=0.5, margin=0.05), "must contain the class"),
        (dict(mu_low=0.6, mu_high=math.inf, value=0.8, margin=0.1), "must contain the class"),
        (dict(mu_low=math.nan, mu_high=0.6, value=0.5, margin=0.1), "mu_low must be finite"),
    ],
)
def test_surface_class_rejects_bad_fields(kwargs, match):
    with pytest.raises(ValueError, match=match):
        SurfaceClass("x", **kwargs)


def test_validate_classes_rejects_unsorted_overlapping_duplicate_empty():
    wet, dry = PAPER_CLASSES[1], PAPER_CLASSES[2]
    with pytest.raises(ValueError, match="sorted by mu_low"):
        validate_classes((dry, wet))
    with pytest.raises(ValueError, match="must not overlap"):
        validate_classes((SurfaceClass("a", 0.1, 0.5, 0.3, 0.2), wet))
    with pytest.raises(ValueError, match="unique names"):
        validate_classes((wet, SurfaceClass("wet", 0.6, 0.8, 0.7, 0.1)))
    with pytest.raises(ValueError, match="at least one"):
        validate_classes(())
    with pytest.raises(ValueError, match="must be a SurfaceClass"):
        validate_classes((wet, (0.6, 1.0, 0.8, 0.2)))
    with pytest.raises(ValueError, match="sorted by mu_low"):
        classify([0.5], (dry, wet))


def _authors_formula(mu):
    """The authors' get_closest_mu_class: value and conservative value (independent reference)."""
    value = 0.15 + np.round((np.asarray(mu) - 0.15) / 0.3) * 0.3
    return value, value - 0.15


def test_authors_table_at_the_turn_surface_gives_045_and_p_030():
    table = class_table("authors")
    wet = table[int(classify(0.4, table))]
    assert (wet.name, wet.value, wet.margin, wet.mu_low) == ("wet", pytest.approx(0.45), 0.15,
                                                            pytest.approx(0.3))
    est = predictive_estimate([0.0, 10.0], [0.4, 0.8], classes=table)
    assert est.mu.tolist() == pytest.approx([0.45, 0.75])
    assert est.mu_low.tolist() == pytest.approx([0.3, 0.6])


def test_authors_table_agrees_with_their_rounding_off_the_class_boundaries():
    mu = np.linspace(0.001, 2.099, 4000)
    mu = mu[np.min(np.abs(mu[:, None] - np.arange(0.3, 2.1, 0.3)[None, :]), axis=1) > 1e-6]
    table = AUTHORS_CLASSES
    idx = classify(mu, table)
    value, low = _authors_formula(mu)
    assert np.array([table[i].value for i in idx]) == pytest.approx(value, abs=1e-12)
    assert np.array([table[i].mu_low for i in idx]) == pytest.approx(low, abs=1e-12)
    # Above 0.9 the formula goes on in steps of 0.3, and so does the table.
    assert table[int(classify(1.0, table))].value == pytest.approx(1.05)
    assert table[int(classify(1.0, table))].mu_low == pytest.approx(0.9)
    with pytest.raises(ValueError, match="mu must lie in a surface class"):
        classify(2.2, table)


def test_authors_table_boundaries_are_half_open():
    # Their np.round (half to even) puts 0.3 and 0.9 in the lower class; here they go up.
    assert classify([0.3, 0.6, 0.9], AUTHORS_CLASSES).tolist() == [1, 2, 3]
    assert _authors_formula([0.3, 0.6, 0.9])[0].tolist() == pytest.approx([0.15, 0.75, 0.75])


def test_class_tables_by_name():
    assert class_table("paper") == PAPER_CLASSES
    assert CLASS_TABLES["authors"] is AUTHORS_CLASSES
    with pytest.raises(ValueError, match="class table must be one of"):
        class_table("camera")
