"""The region the calibration's readings cover, and configurations outside it.

Inside the joint range the readings measured, a prediction interpolates what
was fitted; outside (by more than :data:`OUTSIDE_MARGIN` of the joint's range
between its limits) its std extrapolates the model, and an effect the model
lacks may grow there unseen.
"""
from __future__ import annotations

import numpy as np

#: How far past the measured range a joint is called outside, as a share of its limits' range.
OUTSIDE_MARGIN = 0.1


def joint_range(measurements) -> np.ndarray:
    """Lowest and highest value of each joint over the measured configurations, (N, 2), rad/m."""
    q = measurements.configurations.q[np.unique(measurements.config)]
    return np.column_stack([q.min(axis=0), q.max(axis=0)])


def outside_joints(robot, q, joint_range) -> tuple:
    """The joints of each row that leave the measured range by more than :data:`OUTSIDE_MARGIN`
    of the joint's range between its limits (2π for an unlimited one), in words.

    Parameters
    ----------
    robot : Robot
    q : ndarray, shape (M, N)
        rad (m).
    joint_range : ndarray, shape (N, 2), or None
        The calibration's measured range per joint, rad (m); None: not known ("" each).

    Returns
    -------
    tuple of str
        "" for a row inside, e.g. ``"a2 at 95 (measured -40…60 deg)"``.
    """
    if joint_range is None:
        return ("",) * len(q)
    k = robot.display_factors
    lo, hi = np.asarray(joint_range, float).T * k
    span = np.where(np.isfinite(robot.upper - robot.lower), robot.upper - robot.lower, 2 * np.pi)
    pad = OUTSIDE_MARGIN * span * k
    return tuple(", ".join(f"{j.name} at {v:.4g} (measured {a:.4g}…{b:.4g} "
                           f"{'deg' if j.kind == 'revolute' else 'mm'})"
                           for j, v, a, b, d in zip(robot.joints, row, lo, hi, pad)
                           if v < a - d or v > b + d)
                 for row in np.asarray(q, float) * k)


def outside_flags(robot, q, joint_range) -> tuple:
    """:func:`outside_joints` as a compensated row's flag: "" inside, else the sentence
    ``"outside the measured region: a2 at 95 (measured -40…60 deg); its std extrapolates
    the model, measure poses there"``."""
    return tuple(f"outside the measured region: {w}; its std extrapolates the model, measure "
                 f"poses there" if w else "" for w in outside_joints(robot, q, joint_range))
