"""The configuration registry: one definition of each name, its label and fusion mode."""

from __future__ import annotations

import pytest

from mufusion.configurations import (
    CONFIGURATION_NAMES,
    PAPER_CONFIGURATIONS,
    STANDARD_CONFIGURATION_NAMES,
    Configuration,
    make_configuration,
)


def test_names_are_the_papers_plus_safe_mode_in_order() -> None:
    assert STANDARD_CONFIGURATION_NAMES == ("GT", "L", "P", "F", "F-safe")
    assert CONFIGURATION_NAMES == (*STANDARD_CONFIGURATION_NAMES, "F+shared", "F-safe+shared")
    assert [c.value for c in PAPER_CONFIGURATIONS] == ["GT", "L", "P", "F"]


def test_shared_configurations_name_their_base() -> None:
    assert Configuration.F_SHARED.without_reports is Configuration.F
    assert Configuration.F_SAFE_SHARED.without_reports is Configuration.F_SAFE
    assert Configuration.F.without_reports is Configuration.F
    assert [c.value for c in Configuration if c.shares_reports] == ["F+shared", "F-safe+shared"]
    for c in Configuration:
        assert c.fusion_mode == c.without_reports.fusion_mode


@pytest.mark.parametrize(
    ("name", "mode"),
    [("GT", None), ("L", None), ("P", None), ("F", "paper"), ("F-safe", "safe"),
     ("F+shared", "paper"), ("F-safe+shared", "safe")],
)
def test_fusion_mode_and_built_source_agree(name: str, mode: str | None) -> None:
    configuration = Configuration.parse(name)
    assert configuration.fusion_mode == mode
    source = make_configuration(configuration)
    assert source.name == name
    assert source.configuration is configuration
    assert getattr(source.estimator, "mode", None) == mode
    assert configuration.label.startswith(f"{name} (")


def test_unknown_name_lists_the_allowed_ones() -> None:
    with pytest.raises(ValueError, match=r"configuration must be one of \['GT'"):
        Configuration.parse("F_safe")
