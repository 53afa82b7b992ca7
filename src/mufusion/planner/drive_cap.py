"""No drive above the speed reference: the rear drive's bound per stage in cruise.

The speed reference (:mod:`mufusion.planner.speed_profile`) is the highest speed the road ahead
allows the vehicle, its curves, the friction ahead and the body's fit in the lane included. In
cruise the drive is capped at a heavy vehicle's acceleration (``max_cruise_accel_mps2``) at
every stage. A plan already above the reference could still drive at its first stages and make
up for it with braking at the friction limit further on — a branch the real-time iteration can
follow from step to step, each plan putting the braking off by a stage: the truck of the edge
draw at R 106 m accelerated from 17.1 to 18.6 m/s towards a μ 0.19 section while every plan
braked to the reference's 14.5 m/s a second later, and spun off on it. A cruise controller
does not drive above its set speed; here a stage whose guessed speed is above the reference by
more than :data:`DRIVE_CAP_MARGIN_MPS` gets no drive. Braking stays free: the cap does not ask
the plan to slow down, the tracking cost does.

Off by default (``PlannerConfig.reference_drive_cap``): measured, not adopted. It takes the
spin away (2.15 m out -> 5 cm), but a truck before a feasible 18 m hairpin, whose later stages it
capped, moved its drive to the first stages instead and left the lane by 0.68 m where it had
kept it (docs/decisions/0105).
"""

from __future__ import annotations

import numpy as np

DRIVE_CAP_MARGIN_MPS = 0.5
"""How far above the reference a stage's guessed speed may be and still be driven [m/s]: a plan
that holds the reference keeps its drive against the small overshoots of tracking it."""


def drive_caps_n(
    guess_speed_mps: np.ndarray, reference_mps: np.ndarray, drive_cap_n: float
) -> np.ndarray:
    """Each stage's bound on the rear drive force [N]: ``drive_cap_n``, or 0 where the stage's
    guessed speed is above its reference by more than :data:`DRIVE_CAP_MARGIN_MPS`.

    ``guess_speed_mps`` and ``reference_mps`` hold the speeds at the stages' starts, one per
    stage (the N stages whose inputs are bounded).

    >>> drive_caps_n(np.array([14.0, 15.2, 15.8]), np.array([15.0, 15.0, 15.0]), 6000.0)
    array([6000., 6000.,    0.])
    """
    limit_mps = np.asarray(reference_mps, float) + DRIVE_CAP_MARGIN_MPS
    over = np.asarray(guess_speed_mps, float) > limit_mps
    return np.where(over, 0.0, float(drive_cap_n))
