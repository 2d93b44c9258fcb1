"""Rows of one pose logged a whole turn apart, as a program on a multi-turn joint logs them.

A revolute joint whose limits span more than a turn (a UR's ±360°) stands in the same place
at q and q ± 360°, and a program that takes the nearer equivalent per move
(:mod:`doe_calib.export.turns`) may log a pose's loaded pass a turn from its unloaded pass.
Such rows are one pose, each at its own logged q: an effect by angle (a gear-ratio error)
need not repeat a turn away.
"""
from __future__ import annotations

import numpy as np

#: One turn in file units (deg).
TURN_DEG = 360.0
#: Largest distance (deg) from a whole number of turns that still counts as one: the finest
#: step a controller's log prints (3 decimals), far above rounding a turn in radians.
TURN_TOLERANCE = 1e-3


def turn_joints(robot) -> tuple:
    """Revolute joints (0-based) whose limits span more than one turn."""
    return tuple(k for k, j in enumerate(robot.joints)
                 if j.kind == "revolute" and j.upper - j.lower > 2.0 * np.pi + 1e-9)


def whole_turns(difference, robot) -> np.ndarray:
    """Whole turns k ≠ 0 (to :data:`TURN_TOLERANCE`) in each of ``difference`` (R, N), deg, on
    the :func:`turn_joints`; 0 elsewhere. Shape (R, N), int.

    >>> from types import SimpleNamespace as J
    >>> arm = J(joints=[J(kind="revolute", lower=-7.0, upper=7.0)] * 2)
    >>> whole_turns(np.array([[-360.0, 359.5]]), arm).tolist()
    [[-1, 0]]
    """
    turns = np.zeros(difference.shape, int)
    for k in turn_joints(robot):
        nearest = np.round(difference[:, k] / TURN_DEG)
        whole = np.abs(difference[:, k] - TURN_DEG * nearest) <= TURN_TOLERANCE
        turns[:, k] = np.where(whole, nearest, 0)
    return turns


def turns_note(pose, turns, rows) -> str | None:
    """The poses of ``rows`` logged a whole turn apart (``turns`` (R, N)), in words; None: none."""
    rows = [r for r in rows if turns[r].any()]
    if not rows:
        return None
    poses = list(dict.fromkeys(pose[r] for r in rows))
    joints = ", ".join(f"q{k + 1}" for k in np.flatnonzero(turns[rows].any(axis=0)))
    return (f"{len(poses)} pose(s) logged a whole turn apart ({joints}) between their rows, "
            f"as a program that takes the shortest equivalent angle logs them: "
            f"{', '.join(map(repr, poses[:8]))}{' …' if len(poses) > 8 else ''}; each is kept "
            f"as one pose, every row at its own logged q")
