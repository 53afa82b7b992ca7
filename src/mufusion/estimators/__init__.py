"""mufusion.estimators: emulated camera (predictive) and slip-based (local) friction estimators.

The paper (Sec. IV-A) emulates state-of-the-art estimators by their availability, foresight and
accuracy rather than implementing them; these are those emulations, as pure functions over
arrays (:func:`predictive_estimate`, :func:`classify`) and one small stateful estimator that
holds its latest value (:class:`LocalEstimator`, timed by a :class:`LocalTiming`). Together they
are the vehicle's emulated sensors (:class:`SensorModel`), whose reports reach a friction source
as a :class:`SensorFrame` (:mod:`mufusion.estimators.sensors`). Reports shared by other vehicles
or roadside units (:class:`FrictionReport`), how they travel (:class:`CommModel`) and how they can
be wrong (:class:`WrongReports`) are in :mod:`~mufusion.estimators.shared`,
:mod:`~mufusion.estimators.comm` and :mod:`~mufusion.estimators.misbehaviour`.
"""

from mufusion.estimators.classes import (
    AUTHORS_CLASSES,
    CLASS_TABLES,
    PAPER_CLASSES,
    SurfaceClass,
    class_table,
    classify,
    validate_classes,
)
from mufusion.estimators.comm import MESSAGE_KINDS, CommModel, transmit
from mufusion.estimators.errors import ERROR_MODELS, ErrorModel, check_error_model
from mufusion.estimators.local import (
    LOCAL_MAX_ERROR,
    UTILIZATION_THRESHOLD,
    LocalEstimate,
    LocalEstimator,
)
from mufusion.estimators.misbehaviour import WrongReports, corrupt
from mufusion.estimators.predictive import (
    CAMERA_RANGE_M,
    PredictiveEstimate,
    predictive_estimate,
)
from mufusion.estimators.sensor_model import SensorModel, make_sensor_model
from mufusion.estimators.sensors import (
    SENSOR_CHANNELS,
    CameraReport,
    Channel,
    SensorFrame,
    TrueFriction,
    VehicleSignals,
)
from mufusion.estimators.shared import FrictionReport
from mufusion.estimators.timing import (
    AUTHORS_LOCAL_TIMING,
    LOCAL_TIMINGS,
    PAPER_LOCAL_TIMING,
    LocalTiming,
    local_timing,
)

__all__ = [
    "AUTHORS_CLASSES",
    "AUTHORS_LOCAL_TIMING",
    "CAMERA_RANGE_M",
    "CLASS_TABLES",
    "ERROR_MODELS",
    "LOCAL_MAX_ERROR",
    "LOCAL_TIMINGS",
    "MESSAGE_KINDS",
    "PAPER_CLASSES",
    "PAPER_LOCAL_TIMING",
    "SENSOR_CHANNELS",
    "UTILIZATION_THRESHOLD",
    "CameraReport",
    "Channel",
    "CommModel",
    "ErrorModel",
    "FrictionReport",
    "LocalEstimate",
    "LocalEstimator",
    "LocalTiming",
    "PredictiveEstimate",
    "SensorFrame",
    "SensorModel",
    "SurfaceClass",
    "TrueFriction",
    "VehicleSignals",
    "WrongReports",
    "check_error_model",
    "class_table",
    "classify",
    "corrupt",
    "local_timing",
    "make_sensor_model",
    "predictive_estimate",
    "transmit",
    "validate_classes",
]
