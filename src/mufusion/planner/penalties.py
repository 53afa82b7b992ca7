"""The soft constraints' exact-penalty layout, shared by both backends (planner/ocp.py re-exports
it)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mufusion.planner.config import CostWeights


@dataclass(frozen=True)
class SlackPenalties:
    """Exact-penalty weights of the soft constraints, per slack variable.

    Soft at stages 1..N−1: the corridor bound on ``d`` (one slack), the speed's bounds if the
    OCP has the speed ceiling (``PlannerConfig.speed_ceiling``; one slack: the lower side is
    the minimum speed, priced as the corridor; the upper side the ceiling, priced lower,
    ``CostWeights.speed_ceiling_l1/l2``; without the ceiling the speed's bounds are hard and
    have no slack), the stability envelope's ψ̇ and v_y if the OCP has it (priced as the
    corridor), then the rear polygon's rows (:func:`polygon_rows`), then the
    heading rows if the OCP has them
    (``PlannerConfig.heading_rows``); at the terminal stage N: the corridor bound only. The
    penalty of a slack ``σ ≥ 0`` is ``linear σ + quadratic σ² / 2``; acados multiplies stage
    penalties by ``dt`` (the terminal one not), and the reference backend does the same.
    ``linear_stage``/``quadratic_stage`` price the lower sides, ``*_upper`` the upper sides.
    """

    linear_stage: np.ndarray
    quadratic_stage: np.ndarray
    linear_stage_upper: np.ndarray
    quadratic_stage_upper: np.ndarray
    linear_terminal: np.ndarray
    quadratic_terminal: np.ndarray
    rear_rows: int
    speed_rows: int = 0
    envelope_rows: int = 0

    @property
    def corridor(self) -> slice:
        """Index of the corridor slack within a stage's slacks."""
        return slice(0, 1)

    @property
    def speed(self) -> slice:
        """Index of the speed bounds' slack within a stage's slacks (empty without it)."""
        return slice(1, 1 + self.speed_rows)

    @property
    def envelope(self) -> slice:
        """Indices of the stability envelope's slacks within a stage's slacks (empty without)."""
        return slice(self.speed.stop, self.speed.stop + self.envelope_rows)

    @property
    def rear_polygon(self) -> slice:
        """Indices of the rear-polygon slacks within a stage's slacks."""
        return slice(self.envelope.stop, self.envelope.stop + self.rear_rows)

    @property
    def heading(self) -> slice:
        """Indices of the heading rows' slacks within a stage's slacks (empty without them)."""
        return slice(self.rear_polygon.stop, None)


def slack_penalties(
    weights: CostWeights, rear_rows: int, heading_rows: int = 0, speed_ceiling: bool = False,
    envelope_rows: int = 0,
) -> SlackPenalties:
    """The one place the soft constraints and their penalties are laid out (both backends).

    Examples
    --------
    >>> pen = slack_penalties(CostWeights(), 6, speed_ceiling=True)
    >>> pen.linear_stage.shape, pen.linear_terminal.shape, float(pen.linear_stage[pen.corridor][0])
    ((8,), (1,), 10000.0)
    >>> float(pen.linear_stage_upper[pen.speed][0])
    100.0
    >>> slack_penalties(CostWeights(), 6).rear_polygon  # without the ceiling: no speed slack
    slice(1, 7, None)
    """
    speed_rows = int(speed_ceiling)
    n_stage = 1 + speed_rows + envelope_rows + rear_rows + heading_rows
    linear, quadratic = np.full(n_stage, weights.slack_l1), np.full(n_stage, weights.slack_l2)
    linear_upper, quadratic_upper = linear.copy(), quadratic.copy()
    speed = slice(1, 1 + speed_rows)  # SlackPenalties.speed
    linear_upper[speed], quadratic_upper[speed] = weights.speed_ceiling_l1, weights.speed_ceiling_l2
    return SlackPenalties(
        linear_stage=linear,
        quadratic_stage=quadratic,
        linear_stage_upper=linear_upper,
        quadratic_stage_upper=quadratic_upper,
        linear_terminal=np.full(1, weights.slack_l1),
        quadratic_terminal=np.full(1, weights.slack_l2),
        rear_rows=rear_rows,
        speed_rows=speed_rows,
        envelope_rows=envelope_rows,
    )


def corridor_slack_scale(horizon_steps: int, lead: float) -> np.ndarray:
    """Factors on the corridor slack's penalties at stages 1 … N, shape ``(N,)`` (both backends).

    Stage k's factor is ``lead ** (1 − k/N)``: ``lead`` (almost) at the first stage, 1 at the
    terminal one. A plan's first stages are driven and its later ones planned again, with the
    estimates and the iterate of the steps to come; an equal price at every stage let a plan that
    cannot keep the whole corridor leave it at once rather than where it must
    (docs/decisions/0089).

    Examples
    --------
    >>> corridor_slack_scale(4, 16.0).round(3).tolist()
    [8.0, 4.0, 2.0, 1.0]
    >>> corridor_slack_scale(4, 1.0).tolist()
    [1.0, 1.0, 1.0, 1.0]
    """
    if not (isinstance(horizon_steps, int) and horizon_steps >= 1):
        raise ValueError(f"horizon_steps must be an integer >= 1, got {horizon_steps!r}")
    if not (np.isfinite(lead) and lead >= 1.0):
        raise ValueError(f"lead must be a finite number >= 1, got {lead!r}")
    k = np.arange(1, horizon_steps + 1, dtype=float)
    return np.asarray(float(lead) ** (1.0 - k / horizon_steps))
