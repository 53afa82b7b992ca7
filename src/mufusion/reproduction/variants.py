"""The paper's experiments as data: the scenario variants we run and what the paper reports.

Each :class:`Variant` is one scenario set-up (its overrides of a built-in scenario) run with every
configuration; :data:`PAPER_FACTS` holds the outcomes Svensson & Törngren report (Sec. IV, Fig. 3
and 4) as typed expectations. The verdicts (:mod:`mufusion.reproduction.verdicts`), the report and
the figures read these objects; nothing matches variant names as text.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

from mufusion.configurations import Configuration
from mufusion.reproduction.authors import (
    POPUP_SETTINGS,
    POPUP_UNREPRESENTED,
    TURN_SETTINGS,
    TURN_UNREPRESENTED,
    Setting,
    combined_overrides,
)

C = Configuration


class Criterion(str, Enum):
    """A reported outcome of the paper, checked against a run's metrics."""

    STAYS_IN_LANE = "stays in lane"
    OPPOSING_LANE = "opposing lane"
    COLLISION = "collision"
    IMPACT_SPEED = "impact speed"
    CLEARANCE = "clearance"
    UTILIZATION = "utilisation vs GT"


@dataclass(frozen=True)
class FlagFact:
    """A yes/no outcome: ``metric`` (a boolean metric) should be ``expected``."""

    criterion: Criterion
    metric: str
    expected: bool
    paper: str


@dataclass(frozen=True)
class NumberFact:
    """A number the paper reports: ``metric`` should lie within ``tolerance`` of ``target``."""

    criterion: Criterion
    metric: str
    target: float
    tolerance: float
    unit: str
    paper: str
    as_percent: bool = False


Fact = FlagFact | NumberFact

# Tolerances of the numeric comparisons: the paper gives approximate values ("~17.5 m/s",
# "~0.5 m"); utilisation to 0.1 %, compared within 5 percentage points.
IMPACT_SPEED_TOLERANCE_MPS = 2.5
CLEARANCE_TOLERANCE_M = 0.3
UTILIZATION_TOLERANCE = 0.05
PAPER_IMPACT_SPEED_MPS = 17.5
PAPER_CLEARANCE_M = 0.5


_STAYS = FlagFact(Criterion.STAYS_IN_LANE, "left_lane", False, "stays in its lane")
_TURN_FACTS: dict[Configuration, tuple[Fact, ...]] = {
    C.GT: (_STAYS,),
    C.L: (FlagFact(Criterion.OPPOSING_LANE, "entered_opposing_lane", True,
                   "leaves its lane into the opposing lane"),),
    C.P: (_STAYS,),
    C.F: (_STAYS,),
}
_PASS = FlagFact(Criterion.COLLISION, "collision", False, "passes, no collision")
_CLEARANCE = NumberFact(Criterion.CLEARANCE, "min_clearance_m", PAPER_CLEARANCE_M,
                        CLEARANCE_TOLERANCE_M, "m", f"≈ {PAPER_CLEARANCE_M} m")
_POPUP_FACTS: dict[Configuration, tuple[Fact, ...]] = {
    C.GT: (_PASS, _CLEARANCE),
    C.L: (_PASS, _CLEARANCE),
    C.P: (FlagFact(Criterion.COLLISION, "collision", True, "collides"),
          NumberFact(Criterion.IMPACT_SPEED, "impact_speed_mps", PAPER_IMPACT_SPEED_MPS,
                     IMPACT_SPEED_TOLERANCE_MPS, "m/s", f"≈ {PAPER_IMPACT_SPEED_MPS} m/s")),
    C.F: (_PASS, _CLEARANCE),
}
PAPER_FACTS: dict[str, dict[Configuration, tuple[Fact, ...]]] = {
    "turn": _TURN_FACTS,
    "popup": _POPUP_FACTS,
}
"""Per scenario kind and configuration, the outcomes the paper reports (Sec. IV-C, IV-D)."""


def utilization_facts(p: float, f: float) -> dict[Configuration, NumberFact]:
    """Planned front-force utilisation relative to GT at the comparison instant (Fig. 4k)."""
    return {
        config: NumberFact(Criterion.UTILIZATION, "utilization_vs_gt", target,
                           UTILIZATION_TOLERANCE, "", f"{100 * target:+.1f} %", as_percent=True)
        for config, target in ((C.P, p), (C.F, f))
    }


@dataclass(frozen=True)
class Variant:
    """One scenario set-up of the reproduction, run with every configuration.

    Attributes
    ----------
    key
        Identifier used in run names, summary rows and figure names (``"popup-authors"``).
    scenario
        Built-in scenario it modifies (``"turn"`` or ``"popup"``).
    title
        Heading in the report.
    overrides
        ``dotted.key=value`` overrides of the scenario file.
    paper_vehicle
        Whether it runs the paper's vehicle (the truck): then the paper's numbers apply,
        otherwise only its yes/no outcomes are checked.
    utilization
        The paper's utilisation against GT for this set-up, or empty.
    snapshot_positions_m
        Progress from the start [m] of the top-view snapshots (paper Fig. 3a-h: 0, 15, 30, 55 m;
        Fig. 4a-h: 0, 2, 18, 40 m).
    contrast
        The configuration shown above F in the snapshots (the one that fails in the paper).
    animate
        Whether the reproduction writes GIFs of this variant.
    settings
        The authors' settings this variant applies (:mod:`mufusion.reproduction.authors`); its
        overrides are theirs. Empty for the paper-text variants.
    unrepresented
        What the authors' code set that the variant cannot represent, and why.
    baseline
        Key of the variant it is compared with side by side (the paper-text one), or ``None``.
    """

    key: str
    scenario: str
    title: str
    overrides: tuple[str, ...] = ()
    paper_vehicle: bool = True
    utilization: dict[Configuration, NumberFact] = field(default_factory=dict)
    snapshot_positions_m: tuple[float, ...] = (0.0,)
    contrast: Configuration = C.P
    animate: bool = False
    settings: tuple[Setting, ...] = ()
    unrepresented: tuple[str, ...] = ()
    baseline: str | None = None

    def facts(self, configuration: Configuration) -> tuple[Fact, ...]:
        """The paper's outcomes for ``configuration`` in this variant (none for F-safe)."""
        facts = PAPER_FACTS[self.scenario].get(configuration, ())
        if not self.paper_vehicle:
            facts = tuple(f for f in facts if isinstance(f, FlagFact))
        extra = self.utilization.get(configuration)
        return (*facts, extra) if extra is not None else facts


PAPER_METHOD: tuple[str, ...] = (
    "probing.enabled=false", "lane_recovery.enabled=false", "planner.curve_speed_reference=false",
    "planner.brake_first=false", "planner.steering_rate_limit=false",
    "sim.torque_compensation=false", "planner.load_transfer=false",
    "planner.torque_lag=false", "planner.front_axle_polygon=false", "sim.esc=false",
)
"""The paper's method: a planner that tracks the cruise speed (TAMP), without our additions that
go beyond it: the vehicle's yaw stability control, which the authors' plant did not have
(:mod:`mufusion.vehicle.stability_control`, docs/decisions/0082), friction probing and lane
recovery (:mod:`mufusion.sim.supervision`), the curve-
and friction-aware speed reference (:mod:`mufusion.planner.speed_profile`) and with it the
body's fit (:mod:`mufusion.planner.body_fit`), stopping in front
of an obstacle where possible (:mod:`mufusion.sim.obstacle_response`) and plans whose front
force changes no faster than the steering can turn (:mod:`mufusion.planner.front_force`),
longitudinal forces that follow the torques' lag and axle loads that follow the plan's own
forces (:mod:`mufusion.planner.ocp_state`), a front friction polygon at the friction under the
front axle (:func:`mufusion.planner.ocp.stage_parameters`), and wheel torques commanded ahead
of the brakes' lag (:class:`mufusion.planner.controller.ControllerGains`)."""

TURN_SNAPSHOTS_M = (0.0, 15.0, 30.0, 55.0)
POPUP_SNAPSHOTS_M = (0.0, 2.0, 18.0, 40.0)
# The authors' turn starts where μ drops, 44 m before the arc; their snapshots (and so the
# paper's "s = 0") are about 5 m before the arc, i.e. 39 m after our start.
AUTHORS_TURN_SNAPSHOTS_M = tuple(39.0 + p for p in TURN_SNAPSHOTS_M)

VARIANTS: tuple[Variant, ...] = (
    Variant("turn-paper", "turn", "turn, paper settings", PAPER_METHOD, True, {},
            TURN_SNAPSHOTS_M, C.L, animate=True),
    # At μ = 1.0 the paper's rules give P 1 − 0.6/1.0 = −40 % and F ≈ −5 %.
    Variant("popup-paper", "popup", "pop-up, paper settings (μ = 1.0)", PAPER_METHOD, True,
            utilization_facts(-0.40, -0.05), POPUP_SNAPSHOTS_M, C.P, animate=True),
    # Everything the authors' code set for the turn that a scenario can represent: a pure arc,
    # μ dropping 44 m before it, 15 m/s, their local-estimator timing, error sign and start
    # value, camera classes, surface-dependent tires, and stiffness from μ̂. The paper's
    # outcomes are the facts to check: GT, P, F stay in their lane, L leaves it.
    Variant("turn-authors", "turn", "turn, the authors' settings",
            (*PAPER_METHOD, *combined_overrides(TURN_SETTINGS)), True, {},
            AUTHORS_TURN_SNAPSHOTS_M, C.L,
            settings=TURN_SETTINGS, unrepresented=TURN_UNREPRESENTED, baseline="turn-paper"),
    # The authors' pop-up: μ = 0.89, obstacle 20 m ahead of the CoG and 0.2 m left, their
    # clearance margin, estimator timing, classes and tires. At μ = 0.89 the paper's numbers
    # are exact: P −32.6 %, F −5.6 % (Sec. IV-D).
    Variant("popup-authors", "popup", "pop-up, the authors' settings (μ = 0.89)",
            (*PAPER_METHOD, *combined_overrides(POPUP_SETTINGS)), True,
            utilization_facts(-0.326, -0.056),
            POPUP_SNAPSHOTS_M, C.P, settings=POPUP_SETTINGS, unrepresented=POPUP_UNREPRESENTED,
            baseline="popup-paper"),
    Variant("turn-car", "turn", "turn, passenger car", ("vehicle=car", *PAPER_METHOD), False, {},
            TURN_SNAPSHOTS_M, C.L),
    Variant("popup-car", "popup", "pop-up, passenger car", ("vehicle=car", *PAPER_METHOD), False,
            {},
            POPUP_SNAPSHOTS_M, C.P),
)
"""The reproduction's variants, truck first; ``mufusion reproduce --no-car`` drops the car ones."""

VARIANTS_BY_KEY: dict[str, Variant] = {v.key: v for v in VARIANTS}


def variant(key: str) -> Variant:
    """The variant with ``key``.

    Raises
    ------
    ValueError
        If no variant has that key (the message lists the keys).
    """
    try:
        return VARIANTS_BY_KEY[key]
    except KeyError:
        raise ValueError(f"variant must be one of {list(VARIANTS_BY_KEY)}, got {key!r}") from None


def default_variant(scenario: str) -> Variant | None:
    """The paper-settings variant of a scenario kind (figures of a single run use its layout);
    None for a kind the paper has no variant of (a ``road``)."""
    return next(
        (v for v in VARIANTS if v.scenario == scenario and v.overrides == PAPER_METHOD), None)
