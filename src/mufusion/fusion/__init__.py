"""Fusion of heterogeneous friction estimates by heteroscedastic GP regression (paper Sec. III).

``assemble_inputs`` builds the data (local estimate near the vehicle, predictive classes ahead),
``fuse`` / ``fuse_batch`` / ``GPFusion`` compute the posterior and the conservative estimate μ̂.
See ``docs/fusion.md``.
"""

from mufusion.fusion.assembly import (
    DEFAULT_GRID_M,
    DEFAULT_S_LOCAL_M,
    GRID_STEP_M,
    HORIZON_M,
    LOCAL_GROUP,
    LOCAL_MARGIN,
    FusionData,
    assemble_inputs,
)
from mufusion.fusion.gp import (
    MODES,
    PAPER_LENGTH_SCALE_M,
    PAPER_PRIOR,
    SHARED_ERROR_FRACTION,
    Z95,
    FusedEstimate,
    FusionMode,
    GPFusion,
    GPPrior,
    fuse,
    fuse_batch,
)

__all__ = [
    "DEFAULT_GRID_M",
    "DEFAULT_S_LOCAL_M",
    "GRID_STEP_M",
    "HORIZON_M",
    "LOCAL_GROUP",
    "LOCAL_MARGIN",
    "MODES",
    "PAPER_LENGTH_SCALE_M",
    "PAPER_PRIOR",
    "SHARED_ERROR_FRACTION",
    "Z95",
    "FusedEstimate",
    "FusionData",
    "FusionMode",
    "GPFusion",
    "GPPrior",
    "assemble_inputs",
    "fuse",
    "fuse_batch",
]
