"""Fusion of heterogeneous friction estimates by heteroscedastic GP regression (paper Sec. III).

``assemble_inputs`` builds the data (local estimate near the vehicle, predictive classes ahead),
``fuse`` / ``fuse_batch`` / ``GPFusion`` compute the posterior and the conservative estimate μ̂.
See ``docs/fusion.md``. Modules, upstream first:

* :mod:`~mufusion.fusion.prior`: ``GPPrior``, ``PAPER_PRIOR``, ``Z95`` and the prior's ranges;
* :mod:`~mufusion.fusion.data`: ``FusionData``, ``FusedEstimate``, modes, the declared physical
  ranges, the noise floor and the checks at the boundary;
* :mod:`~mufusion.fusion.engine`: ``PosteriorEngine``, the linear algebra and its caches;
* :mod:`~mufusion.fusion.safe`: safe mode (grouped noise, hard-bound envelope);
* :mod:`~mufusion.fusion.assembly`: ``assemble_inputs`` (and its batch form) and the grid;
* :mod:`~mufusion.fusion.reports`: shared reports as input (``ReportData``, ``report_data``,
  ``SharedSettings``: age, position error, sender cap);
* :mod:`~mufusion.fusion.shared_fusion`: the fusion with reports (trust test, one-sided rule,
  safe mode's hard bound with reports; decision 0060);
* :mod:`~mufusion.fusion.core`: ``fuse``, ``GPFusion``; :mod:`~mufusion.fusion.batch`:
  ``fuse_batch``.
"""

from mufusion.estimators.shared import DEFAULT_SHARED, SharedSettings
from mufusion.fusion.assembly import (
    DEFAULT_GRID_M,
    DEFAULT_S_LOCAL_M,
    GRID_STEP_M,
    HORIZON_M,
    LOCAL_GROUP,
    LOCAL_MARGIN,
    FusionDataBatch,
    assemble_inputs,
    assemble_inputs_batch,
    declared_central_value,
    declared_upper_bound,
    local_surface_bound,
)
from mufusion.fusion.batch import fuse_batch
from mufusion.fusion.core import GPFusion, fuse
from mufusion.fusion.data import (
    MARGIN_RANGE,
    MODES,
    MU_RANGE,
    NOISE_STD_FLOOR,
    POSITION_RANGE_M,
    FusedEstimate,
    FusionData,
    FusionMode,
)
from mufusion.fusion.engine import PosteriorEngine
from mufusion.fusion.prior import (
    LENGTH_SCALE_RANGE_M,
    PAPER_LENGTH_SCALE_M,
    PAPER_PRIOR,
    PRIOR_MEAN_RANGE,
    PRIOR_STD_RANGE,
    Z95,
    GPPrior,
)
from mufusion.fusion.reports import ReportData, report_data
from mufusion.fusion.safe import SHARED_ERROR_FRACTION
from mufusion.fusion.shared_fusion import ReportScreen, screen_reports

__all__ = [
    "DEFAULT_GRID_M",
    "DEFAULT_SHARED",
    "DEFAULT_S_LOCAL_M",
    "GRID_STEP_M",
    "HORIZON_M",
    "LENGTH_SCALE_RANGE_M",
    "LOCAL_GROUP",
    "LOCAL_MARGIN",
    "MARGIN_RANGE",
    "MODES",
    "MU_RANGE",
    "NOISE_STD_FLOOR",
    "PAPER_LENGTH_SCALE_M",
    "PAPER_PRIOR",
    "POSITION_RANGE_M",
    "PRIOR_MEAN_RANGE",
    "PRIOR_STD_RANGE",
    "SHARED_ERROR_FRACTION",
    "Z95",
    "FusedEstimate",
    "FusionData",
    "FusionDataBatch",
    "FusionMode",
    "GPFusion",
    "GPPrior",
    "PosteriorEngine",
    "ReportData",
    "ReportScreen",
    "SharedSettings",
    "assemble_inputs",
    "assemble_inputs_batch",
    "declared_central_value",
    "declared_upper_bound",
    "fuse",
    "fuse_batch",
    "local_surface_bound",
    "report_data",
    "screen_reports",
]
