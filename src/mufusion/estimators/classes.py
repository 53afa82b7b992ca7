"""Road-surface classes of the camera (predictive) friction estimator, as data.

A class maps an interval of the true friction coefficient to what the camera-based estimator
reports for it: the class value (its mean, used as fusion input) with a 95 % margin, and the
class's lowest μ (the conservative value of the predictive-only configuration P).

Source: paper Sec. IV-B, the equations of configurations P and F, with the classes of
Table I (dry, wet, snow/ice):

==========  =====================  ======  ======  =====
class       μ interval             value   margin  low
==========  =====================  ======  ======  =====
snow/ice    0.1 ≤ μ < 0.4          0.25    0.15    0.1
wet         0.4 ≤ μ < 0.6          0.5     0.1     0.4
dry         0.6 ≤ μ (no top)       0.8     0.2     0.6
==========  =====================  ======  ======  =====

Boundary convention
-------------------
Every class is the half-open interval ``[mu_low, mu_high)``, the paper's convention for wet and
snow/ice, applied to dry as well. The paper writes dry as ``0.6 < μ``, which leaves μ = 0.6 in no
class; here **μ = 0.6 is dry**. That single point is the only deviation, and it keeps P
conservative (it reports 0.6 = μ) and F's input covering the truth (0.8 ± 0.2 contains 0.6).
The last class is closed at its top when the top is finite, so a table ending at 1.0 covers 1.0.

Top of the dry class
--------------------
The paper gives dry no upper bound, so ``mu_high = inf`` here: any μ ≥ 0.6 is dry (the scenarios
admit μ up to 1.5). The dry margin 0.2 covers [0.6, 1.0], the prior's range (paper Sec. III);
above μ = 1.0 the class value 0.8 under-estimates by more than the margin, which errs on the safe
side. Below μ = 0.1 no class applies and :func:`classify` raises.

The authors' scheme
-------------------
The authors' code (``road_perception.py``, ``get_closest_mu_class`` in their ``tamp_ws``
repository) rounds instead: class value ``0.15 + round((μ − 0.15)/0.3)·0.3``, conservative value
(P) that minus 0.15, i.e. classes of width 0.3 centred on 0.15, 0.45, 0.75 with margin 0.15
(:data:`AUTHORS_CLASSES`). For μ = 0.4 that is 0.45 ± 0.15 and P = 0.30 (the paper's table: 0.5 ±
0.1 and P = 0.4). Their comment names three classes (snow/ice, wet, dry up to 0.9) and a sanity
check was meant to warn on any other value, but the check is ineffective (it tests
``any(values)``), so above 0.9 the formula silently goes on: μ ∈ [0.9, 1.2) gives 1.05 ± 0.15 with
P = 0.9, and so on. The preset follows the code, not the comment: it continues the rounding in
steps of 0.3 up to μ = 2.1 (the local estimator admits μ ≤ 2). Their own scenarios (μ = 0.4, 0.5,
0.8, 0.89) all lie below 0.9, where both readings agree. The snow/ice class starts at 0, so P
reports 0 there (the configurations clip μ̂ to a small positive value). Exactly at 0.3 and 0.9
their ``np.round`` (half to even) puts μ in the lower class and at 0.6 in the upper one; here every
class is half-open ``[low, high)``, so 0.3 and 0.9 go up: three points, none used by a scenario.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

# Slack on the coverage check of a class's margin [-]: 0.8 − 0.2 is 0.6000000000000001 in binary.
_COVER_TOL = 1e-9


@dataclass(frozen=True)
class SurfaceClass:
    """One road-surface class of the camera estimator.

    Attributes
    ----------
    name : str
        Label, e.g. ``"dry"``.
    mu_low : float
        Lowest μ of the class [-], inclusive, ≥ 0; also the conservative value P reports.
    mu_high : float
        Upper end of the class [-], exclusive (inclusive for the last class of a table);
        ``math.inf`` for an open-ended top class.
    value : float
        μ the camera reports for the class (its mean) [-].
    margin : float
        Half-width of the 95 % interval around ``value`` [-]; ``value ± margin`` must contain
        ``[mu_low, mu_high]`` (paper Sec. III: the margin encompasses the whole class), except
        above a top that is infinite.

    Raises
    ------
    ValueError
        If a bound is not finite (``mu_high`` may be ``inf``), ``0 ≤ mu_low < mu_high`` fails,
        ``value`` lies outside the class, ``margin`` is not > 0 or does not cover the class.

    Examples
    --------
    >>> SurfaceClass("wet", 0.4, 0.6, 0.5, 0.1).mu_low
    0.4
    """

    name: str
    mu_low: float
    mu_high: float
    value: float
    margin: float

    def __post_init__(self) -> None:
        for field_name in ("mu_low", "mu_high", "value", "margin"):
            object.__setattr__(self, field_name, float(getattr(self, field_name)))
        where = f"SurfaceClass {self.name!r}"
        for field_name in ("mu_low", "value", "margin"):
            if not math.isfinite(getattr(self, field_name)):
                raise ValueError(
                    f"{where}: {field_name} must be finite, got {getattr(self, field_name)!r}"
                )
        if math.isnan(self.mu_high):
            raise ValueError(f"{where}: mu_high must be a number or inf, got nan")
        if not 0.0 <= self.mu_low < self.mu_high:
            raise ValueError(
                f"{where}: need 0 ≤ mu_low < mu_high, got mu_low={self.mu_low}, "
                f"mu_high={self.mu_high}"
            )
        if not self.mu_low <= self.value <= self.mu_high:
            raise ValueError(
                f"{where}: value must lie in [mu_low, mu_high] = [{self.mu_low}, {self.mu_high}], "
                f"got {self.value}"
            )
        if not self.margin > 0.0:
            raise ValueError(f"{where}: margin must be > 0, got {self.margin}")
        top = self.mu_high if math.isfinite(self.mu_high) else self.mu_low
        if (
            self.value - self.margin > self.mu_low + _COVER_TOL
            or self.value + self.margin < top - _COVER_TOL
        ):
            raise ValueError(
                f"{where}: value ± margin = [{self.value - self.margin:.6g}, "
                f"{self.value + self.margin:.6g}] must contain the class "
                f"[{self.mu_low}, {self.mu_high}] (paper Sec. III)"
            )


# Paper Sec. IV-B (configurations P and F), sorted by increasing μ; index = class index.
PAPER_CLASSES: tuple[SurfaceClass, ...] = (
    SurfaceClass("snow/ice", mu_low=0.1, mu_high=0.4, value=0.25, margin=0.15),
    SurfaceClass("wet", mu_low=0.4, mu_high=0.6, value=0.5, margin=0.1),
    SurfaceClass("dry", mu_low=0.6, mu_high=math.inf, value=0.8, margin=0.2),
)

# The authors' code: value 0.15 + round((μ − 0.15)/0.3)·0.3, P = value − 0.15 (module docstring).
_AUTHORS_WIDTH = 0.3
AUTHORS_CLASSES: tuple[SurfaceClass, ...] = tuple(
    SurfaceClass(
        name,
        mu_low=round(k * _AUTHORS_WIDTH, 10),
        mu_high=round((k + 1) * _AUTHORS_WIDTH, 10),
        value=round((k + 0.5) * _AUTHORS_WIDTH, 10),
        margin=_AUTHORS_WIDTH / 2.0,
    )
    for k, name in enumerate(
        ("snow/ice", "wet", "dry", "0.9-1.2", "1.2-1.5", "1.5-1.8", "1.8-2.1")
    )
)

CLASS_TABLES: dict[str, tuple[SurfaceClass, ...]] = {
    "paper": PAPER_CLASSES,
    "authors": AUTHORS_CLASSES,
}


def class_table(name: str) -> tuple[SurfaceClass, ...]:
    """Return a camera class table by name (validated).

    Parameters
    ----------
    name : {"paper", "authors"}
        ``"paper"``: Table I (:data:`PAPER_CLASSES`); ``"authors"``: the rounding scheme of the
        authors' code (:data:`AUTHORS_CLASSES`).

    Raises
    ------
    ValueError
        If ``name`` is unknown; the message lists the tables.

    Examples
    --------
    >>> wet = class_table("authors")[int(classify(0.4, class_table("authors")))]
    >>> round(wet.value, 2), wet.margin, wet.mu_low
    (0.45, 0.15, 0.3)
    """
    try:
        table = CLASS_TABLES[name]
    except KeyError:
        raise ValueError(
            f"class table must be one of {sorted(CLASS_TABLES)}, got {name!r}"
        ) from None
    return validate_classes(table)


def validate_classes(classes: Sequence[SurfaceClass]) -> tuple[SurfaceClass, ...]:
    """Check a class table and return it as a tuple.

    Parameters
    ----------
    classes : sequence of SurfaceClass
        Classes sorted by increasing ``mu_low``, non-overlapping (gaps are allowed: μ in a gap
        is unclassifiable), with unique names.

    Returns
    -------
    tuple of SurfaceClass

    Raises
    ------
    ValueError
        If ``classes`` is empty, holds a non-SurfaceClass, is unsorted, overlapping, has an
        infinite top on a class that is not the last, or repeats a name.

    Examples
    --------
    >>> [c.name for c in validate_classes(PAPER_CLASSES)]
    ['snow/ice', 'wet', 'dry']
    """
    table = tuple(classes)
    if not table:
        raise ValueError("classes must hold at least one SurfaceClass, got none")
    for i, c in enumerate(table):
        if not isinstance(c, SurfaceClass):
            raise ValueError(f"classes[{i}] must be a SurfaceClass, got {type(c).__name__}")
    names = [c.name for c in table]
    if len(set(names)) != len(names):
        raise ValueError(f"classes must have unique names, got {names}")
    for i, (a, b) in enumerate(itertools.pairwise(table)):
        if b.mu_low < a.mu_high:
            raise ValueError(
                f"classes must be sorted by mu_low and must not overlap: classes[{i}] "
                f"{a.name!r} [{a.mu_low}, {a.mu_high}) and classes[{i + 1}] {b.name!r} "
                f"[{b.mu_low}, {b.mu_high})"
            )
    return table


def class_bounds(classes: Sequence[SurfaceClass]) -> tuple[float, float]:
    """The lowest and highest μ a (validated) class table covers [-]."""
    return classes[0].mu_low, classes[-1].mu_high


def classify(mu: np.ndarray | float, classes: Sequence[SurfaceClass] = PAPER_CLASSES) -> np.ndarray:
    """Index of the surface class of each friction coefficient.

    Parameters
    ----------
    mu : array_like
        True friction coefficients [-], any shape.
    classes : sequence of SurfaceClass
        Class table (see :func:`validate_classes`); default the paper's.

    Returns
    -------
    numpy.ndarray of int
        Same shape as ``mu``; index into ``classes``.

    Raises
    ------
    ValueError
        If ``classes`` is invalid, or any ``mu`` is NaN or lies in no class (below the lowest
        class, in a gap, or above a finite top); the message names ``mu`` and the covered range.

    Examples
    --------
    >>> classify([0.1, 0.39, 0.4, 0.6, 1.0]).tolist()
    [0, 0, 1, 2, 2]
    """
    table = validate_classes(classes)
    values = np.asarray(mu, dtype=float)
    lows = np.array([c.mu_low for c in table])
    highs = np.array([c.mu_high for c in table])
    index = np.searchsorted(lows, values, side="right") - 1
    safe = np.clip(index, 0, len(table) - 1)
    inside = (index >= 0) & (values < highs[safe])
    # The last class is closed at a finite top (e.g. a table ending at exactly μ = 1.0).
    inside |= (index == len(table) - 1) & (values == highs[-1])
    if not np.all(inside):
        bad = values[~inside]
        lo, hi = class_bounds(table)
        raise ValueError(
            f"mu must lie in a surface class, covered range [{lo}, {hi}] "
            f"({', '.join(f'{c.name} [{c.mu_low}, {c.mu_high})' for c in table)}); "
            f"got {bad.size} value(s) outside, e.g. {bad.ravel()[0]!r}"
        )
    return safe.astype(int)
