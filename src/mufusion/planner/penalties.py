"""The soft constraints' exact-penalty layout, shared by both backends (planner/ocp.py re-exports
it)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mufusion.planner.config import CostWeights


@dataclass(frozen=True)
class SlackPenalties:
    """Exact-penalty weights of the soft constraints, per slack variable (lower = upper side).

    Soft at stages 1..N−1: the corridor bound on ``d`` (one slack), then the rear polygon's rows
    (:func:`polygon_rows`), then the heading rows if the OCP has them
    (``PlannerConfig.heading_rows``); at the terminal stage N: the corridor bound only. The
    penalty of a slack ``σ ≥ 0`` is ``linear σ + quadratic σ² / 2``; acados multiplies stage
    penalties by ``dt`` (the terminal one not), and the reference backend does the same.
    """

    linear_stage: np.ndarray
    quadratic_stage: np.ndarray
    linear_terminal: np.ndarray
    quadratic_terminal: np.ndarray
    rear_rows: int

    @property
    def corridor(self) -> slice:
        """Index of the corridor slack within a stage's slacks."""
        return slice(0, 1)

    @property
    def rear_polygon(self) -> slice:
        """Indices of the rear-polygon slacks within a stage's slacks."""
        return slice(1, 1 + self.rear_rows)

    @property
    def heading(self) -> slice:
        """Indices of the heading rows' slacks within a stage's slacks (empty without them)."""
        return slice(1 + self.rear_rows, None)


def slack_penalties(
    weights: CostWeights, rear_rows: int, heading_rows: int = 0
) -> SlackPenalties:
    """The one place the soft constraints and their penalties are laid out (both backends).

    Examples
    --------
    >>> pen = slack_penalties(CostWeights(), 6)
    >>> pen.linear_stage.shape, pen.linear_terminal.shape, float(pen.linear_stage[pen.corridor][0])
    ((7,), (1,), 10000.0)
    """
    n_stage = 1 + rear_rows + heading_rows
    return SlackPenalties(
        linear_stage=np.full(n_stage, weights.slack_l1),
        quadratic_stage=np.full(n_stage, weights.slack_l2),
        linear_terminal=np.full(1, weights.slack_l1),
        quadratic_terminal=np.full(1, weights.slack_l2),
        rear_rows=rear_rows,
    )
