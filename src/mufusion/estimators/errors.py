"""Error models of the emulated friction estimators (paper Sec. IV-A, Table I).

The paper emulates the estimators instead of implementing them and sets their errors
adversarially: worst-case over-estimation in the low-μ turn, worst-case under-estimation in the
collision-avoidance scenario. The models, for an estimator whose worst-case error is ``m``
(the local estimator's ``max{|e_l|}``, the camera class's margin ``m_p``):

``"none"``
    No added error. The local estimate is exact; the camera reports its class value (the class
    mean, the paper's emulation), whose error is whatever the true μ's place in the class makes it.
``"worst_over"``
    The estimate is ``μ_gt + m``: the largest over-estimation the method admits.
``"worst_under"``
    The estimate is ``μ_gt − m``: the largest under-estimation.
``"random"``
    The estimate is ``μ_gt + e`` with ``e ~ U(−m, m)`` drawn from a seeded
    :class:`numpy.random.Generator` passed in by the caller (no hidden randomness).
"""

from __future__ import annotations

from typing import Literal, get_args

import numpy as np

ErrorModel = Literal["none", "worst_over", "worst_under", "random"]
ERROR_MODELS: tuple[str, ...] = get_args(ErrorModel)


def check_error_model(
    name: str, error: str, rng: np.random.Generator | None
) -> np.random.Generator | None:
    """Validate an error model and its random generator.

    Parameters
    ----------
    name : str
        Argument name used in messages (e.g. ``"error"``, ``"local_error"``).
    error : str
        One of :data:`ERROR_MODELS`.
    rng : numpy.random.Generator or None
        Required when ``error == "random"``.

    Returns
    -------
    numpy.random.Generator or None
        ``rng``.

    Raises
    ------
    ValueError
        If ``error`` is unknown, or it is ``"random"`` without a Generator.
    """
    if error not in ERROR_MODELS:
        raise ValueError(f"{name} must be one of {list(ERROR_MODELS)}, got {error!r}")
    if rng is not None and not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng must be a numpy.random.Generator or None, got {type(rng).__name__}")
    if error == "random" and rng is None:
        raise ValueError(
            f"{name}='random' needs a seeded numpy.random.Generator as rng "
            "(e.g. numpy.random.default_rng(0)); got rng=None"
        )
    return rng


def signed_error(error: str, margin: np.ndarray | float, rng: np.random.Generator | None):
    """Error ``e`` added to the true μ under a non-``"none"`` model, for margins ``margin``.

    ``"none"`` gives 0 (callers that report a class value handle it themselves); ``"random"``
    draws one ``U(−margin, margin)`` value per element of ``margin``.
    """
    m = np.asarray(margin, dtype=float)
    if error == "worst_over":
        return m.copy() if m.ndim else float(m)
    if error == "worst_under":
        return -m if m.ndim else -float(m)
    if error == "random":
        if rng is None:
            raise ValueError("rng: the 'random' error model needs a numpy.random.Generator")
        e = rng.uniform(-1.0, 1.0, size=m.shape) * m
        return e if m.ndim else float(e)
    return np.zeros_like(m) if m.ndim else 0.0
