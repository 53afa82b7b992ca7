"""The sampling augmentation scores a violation by how far it goes, not by how long.

Two roll-outs of a pop-up 1.0 m left of the lane centre (the car at 20 m/s): one passes on the
right and overshoots the road's edge by 0.155 m for the rest of the horizon (the tracking law's
overshoot; the OCP pulls it back), the other stays on the road and runs 0.3 m into the obstacle.
Summed over the stages, the overshoot (6.2 m over 40 stages) outweighed the overlap (0.3 m over
five), and the guess the corridor takes its side from ran into the obstacle
(docs/decisions/0073).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import mufusion.planner.sampling as sampling
from mufusion.planner.config import PlannerConfig, PlannerObstacle
from mufusion.planner.footprint import stage_violations_m
from mufusion.vehicle.params import CAR
from mufusion.vehicle.planner_model import N_INPUTS, N_STATES, State

N = 40
ROAD = (-0.845, 4.345)
OBSTACLE = PlannerObstacle(s_m=40.0, d_m=1.0, length_m=1.0, width_m=1.0)


def _trajectory(d_m: float) -> np.ndarray:
    x = np.zeros((N + 1, N_STATES))
    x[:, State.s] = 2.0 * np.arange(N + 1)
    x[:, State.vx] = 20.0
    x[1:, State.d] = d_m
    return x


def _choose(monkeypatch: pytest.MonkeyPatch, candidates: list[np.ndarray]) -> np.ndarray:
    xs = np.stack(candidates, axis=2)
    us = np.zeros((N, N_INPUTS, len(candidates)))
    monkeypatch.setattr(sampling, "candidate_rollouts", lambda *a, **k: (xs, us))
    into = _trajectory(1.0)  # the shifted plan: straight into the obstacle
    guess, _, sampled = sampling.sampled_guess(
        into[0], into, np.zeros((N, N_INPUTS)), lambda s: np.zeros_like(s),
        lambda s: np.full_like(s, 0.8), [OBSTACLE], 20.0, 0.0, *ROAD, CAR,
        PlannerConfig(horizon_steps=N), sampling.SamplingConfig(), continuing=False,
    )
    assert sampled
    return guess


def test_an_overshoot_beyond_the_road_never_outweighs_a_deeper_overlap(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    right, into = _trajectory(-1.0), _trajectory(2.5)
    both = np.stack([right, into], axis=2)
    road, overlap = stage_violations_m(both, [OBSTACLE], *ROAD, CAR, 0.5, 0.1)
    assert road[:, 0].sum() > road[:, 1].sum() + overlap[:, 1].sum()  # what the sums preferred
    assert road.max(axis=0).tolist() == pytest.approx([0.155, 0.0])
    assert overlap.max(axis=0).tolist() == pytest.approx([0.0, 1.805 - 1.5])
    for order in ([right, into], [into, right]):
        assert _choose(monkeypatch, order)[-1, State.d] == pytest.approx(-1.0)


def test_without_an_overlap_the_road_and_tracking_decide(monkeypatch: pytest.MonkeyPatch) -> None:
    far, near = _trajectory(-1.0), _trajectory(-0.82)  # both clear the obstacle
    assert _choose(monkeypatch, [far, near])[-1, State.d] == pytest.approx(-0.82)


def test_a_diverged_candidate_is_discarded_without_a_warning(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # A roll-out that blew up (its lateral offset overflowing the violation's weight) ranks last
    # and says nothing on the terminal: a campaign's log is for its runs.
    diverged = _trajectory(-1.0)
    diverged[5:, State.d] = 1e306
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert _choose(monkeypatch, [diverged, _trajectory(-0.82)])[-1, State.d] == pytest.approx(
            -0.82)
