"""A friction source reads the sensor frame; only a source declaring the truth channel (GT) gets
the true μ, and plug-ins that cannot work are refused with their name before any run."""

from __future__ import annotations

import dataclasses
import typing

import numpy as np
import pytest

from mufusion.configurations import (
    CONFIGURATION_NAMES,
    FrictionEstimator,
    channels_of,
    make_configuration,
    make_estimator,
    step_source,
)
from mufusion.configurations.plugins import PluginError, check_friction_spec, make_friction_plugin
from mufusion.estimators import (
    CameraReport,
    Channel,
    SensorFrame,
    SensorModel,
    TrueFriction,
    VehicleSignals,
)

GRID_M = np.arange(0.0, 51.0, 1.0)


def _fields(record: type) -> dict[str, object]:
    hints = typing.get_type_hints(record)
    return {f.name: hints[f.name] for f in dataclasses.fields(record)}


@pytest.mark.parametrize("record", [SensorFrame, CameraReport, VehicleSignals])
def test_no_sensor_record_carries_the_true_friction(record: type) -> None:
    for name, hint in _fields(record).items():
        assert not any(word in name for word in ("true", "truth", "gt")), (record, name)
        assert "TrueFriction" not in str(hint), (record, name)


@pytest.mark.parametrize("name", CONFIGURATION_NAMES)
def test_only_gt_declares_the_truth_channel(name: str) -> None:
    assert (Channel.TRUTH in channels_of(make_estimator(name))) == (name == "GT")


class _Recording(FrictionEstimator):
    def __init__(self, channels: frozenset[Channel]) -> None:
        self.channels = channels  # type: ignore[misc]
        self.calls: list[tuple] = []

    def step(self, *args):
        self.calls.append(args)
        return np.full(args[0].s_ahead_m.shape, 0.5)


@pytest.mark.parametrize(
    "channels", [frozenset(), frozenset({Channel.CAMERA_CLASSES, Channel.CAMERA_MU})]
)
def test_a_source_without_the_truth_channel_is_handed_the_frame_alone(channels) -> None:
    source = _Recording(channels)
    estimate = step_source(source, SensorModel(), GRID_M, np.full(GRID_M.size, 0.8), 0.7)
    (args,) = source.calls
    assert len(args) == 1 and isinstance(args[0], SensorFrame)
    assert (args[0].camera is not None) == bool(channels)
    # The μ̂ of a source that returns an array comes back as an estimate with the slip report.
    assert np.all(estimate.mu_hat == 0.5) and estimate.local_available


def test_a_source_declaring_the_truth_channel_gets_the_truth_beside_the_frame() -> None:
    source = _Recording(frozenset({Channel.TRUTH}))
    mu = np.linspace(0.8, 0.3, GRID_M.size)
    step_source(source, SensorModel(), GRID_M, mu, 0.0)
    (args,) = source.calls
    assert isinstance(args[0], SensorFrame) and isinstance(args[1], TrueFriction)
    assert np.array_equal(args[1].mu, mu)


@pytest.mark.parametrize("name", CONFIGURATION_NAMES)
def test_two_roads_the_sensors_cannot_tell_apart_give_one_estimate_except_to_gt(name) -> None:
    # 0.8 and 0.85 lie in one class; the slip estimator is not excited and holds its μ̂_0.
    a, b = (make_configuration(name, initial_local_mu=0.7).step(GRID_M, np.full(GRID_M.size, mu),
                                                                0.1) for mu in (0.8, 0.85))
    assert np.array_equal(a.mu_hat, b.mu_hat) == (name != "GT")


def test_a_non_finite_estimate_is_refused_naming_the_source() -> None:
    class Broken(FrictionEstimator):
        def step(self, frame):
            return np.full(frame.s_ahead_m.shape, np.nan)

    with pytest.raises(ValueError, match="'Broken' produced a non-finite"):
        step_source(Broken(), SensorModel(), GRID_M, np.full(GRID_M.size, 0.8), 0.0)


class NoStep:
    pass


class WrongArity(FrictionEstimator):
    def step(self):
        return None


class BadChannels(FrictionEstimator):
    channels = frozenset({"lidar"})  # type: ignore[assignment]

    def step(self, frame):
        return None


class Raises(FrictionEstimator):
    def __init__(self) -> None:
        raise RuntimeError("no calibration file")


@pytest.mark.parametrize(
    ("spec", "match"),
    [
        ("no_such_module_xyz:Source", "module 'no_such_module_xyz' failed to import"),
        (f"{__name__}:Missing", "has no attribute 'Missing'"),
        (f"{__name__}:NoStep", "is not a friction source: NoStep has no callable step"),
        (f"{__name__}:WrongArity", "step must accept 1 positional argument"),
        (f"{__name__}:BadChannels", "channels of .* must be a collection of"),
        (f"{__name__}:Raises", "making it failed: RuntimeError: no calibration file"),
        ("Q", "'Q' is neither a built-in configuration"),
    ],
)
def test_an_unusable_plugin_is_refused_naming_it(spec: str, match: str) -> None:
    with pytest.raises(PluginError, match=match) as caught:
        check_friction_spec(spec)
    assert repr(spec) in str(caught.value)


def make_source() -> _Recording:
    return _Recording(frozenset())


@pytest.mark.parametrize("spec", [f"{__name__}:make_source", "F-safe"])
def test_a_usable_plugin_or_builtin_is_its_own_label(spec: str) -> None:
    assert check_friction_spec(spec) == spec


def test_an_installed_package_names_its_source_by_an_entry_point(tmp_path, monkeypatch) -> None:
    # A package as pip installs it: its module and a dist-info declaring the entry point.
    (tmp_path / "my_estimators.py").write_text(
        "import numpy as np\n"
        "class Constant:\n"
        "    channels = frozenset()\n"
        "    def step(self, frame):\n"
        "        return np.full(frame.s_ahead_m.shape, 0.3)\n"
    )
    info = tmp_path / "my_estimators-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: my-estimators\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(
        "[mufusion.friction_sources]\nconstant = my_estimators:Constant\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    assert check_friction_spec("constant") == "constant"
    source = make_friction_plugin("constant")
    estimate = step_source(source, SensorModel(), GRID_M, np.full(GRID_M.size, 0.8), 0.0)
    assert np.all(estimate.mu_hat == 0.3)
    with pytest.raises(PluginError, match="'constan' is neither a built-in configuration"):
        check_friction_spec("constan")
