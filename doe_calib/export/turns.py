"""Equivalent angles of joints with more than one turn: q + 2πk chosen for short moves.

A revolute joint whose limits span more than one turn (a UR arm's ±360°)
stands in the same place at q and at q ± 2π. Once the visiting order is
fixed, each such joint's angle at each visit is chosen among its
equivalents inside the limits so that the joint's **total travel** over the
program,

    Σ_i |q_j(i+1) − q_j(i)|        (from the start position to the end one),

is least — for each joint separately, exactly, by dynamic programming over
the visits (a shortest path through the layers of equivalents). Total travel
per joint, not the time of the slowest axis, is the cost: it separates over
the joints, so the optimum is exact; shorter travel of every joint also
shortens every synchronous move it is part of.

An equivalent other than the design's own angle must stay ``margin`` inside
the limits (the pre-pose step), and is used only on joints on which the
model's marker positions are the same a full turn away
(:func:`periodic_joints`): geometry, compliances, cyclic errors with whole
harmonics are; a gear-ratio error or a compliance by angle in bins is not,
and those joints keep the design's angles.
"""
from __future__ import annotations

import numpy as np

from doe_calib.io.measurements import Configurations
from doe_calib.model.evaluation import evaluate

TURN = 2.0 * np.pi
#: Largest difference of a marker's position a full turn away that counts as the same, m.
SAME_POSITION = 1e-9


def turn_joints(robot) -> tuple:
    """Revolute joints (0-based) whose limits span more than one turn."""
    return tuple(k for k, j in enumerate(robot.joints)
                 if j.kind == "revolute" and j.upper - j.lower > TURN + 1e-9)


def periodic_joints(model, joints, rng=None) -> tuple:
    """Those of ``joints`` on which ``model``'s marker positions have period 2π.

    Checked numerically: marker positions at 8 random configurations (inside
    the limits, with a random wrench) and random parameter values (nominal ±
    3 scales) compared with the same one turn up and one turn down.

    Parameters
    ----------
    model : Model
    joints : sequence of int
    rng : numpy.random.Generator, optional

    Returns
    -------
    tuple of int
    """
    rng = np.random.default_rng(0) if rng is None else rng
    robot = model.robot
    lower, upper = np.clip(robot.lower, -np.pi, None), np.clip(robot.upper, None, np.pi)
    q = rng.uniform(lower, upper, size=(8, robot.n_joints))
    wrench = rng.normal(0.0, 50.0, size=(8, 6))
    nominal = model.nominal()
    values = nominal.values + 3.0 * rng.standard_normal(len(nominal.values)) * np.array(
        [p.scale for p in nominal.parameters])
    here = evaluate(model.markers, Configurations.from_arrays(q, wrench), values)[0]
    out = []
    for k in joints:
        same = True
        for turn in (TURN, -TURN):
            moved = q.copy()
            moved[:, k] += turn
            there = evaluate(model.markers, Configurations.from_arrays(moved, wrench), values)[0]
            same = same and bool(np.max(np.abs(there - here)) <= SAME_POSITION)
        if same:
            out.append(k)
    return tuple(out)


def _equivalents(value: float, lower: float, upper: float, margin: float) -> np.ndarray:
    """``value`` and each ``value + 2πk`` at least ``margin`` inside [lower, upper]."""
    k = np.arange(-3, 4)
    shifted = value + TURN * k
    keep = (k == 0) | ((shifted >= lower + margin) & (shifted <= upper - margin))
    return shifted[keep]


def shortest_turns(q, joints, lower, upper, margin, start=None, end=None) -> np.ndarray:
    """``q`` with each joint of ``joints`` turned by whole turns for least total travel.

    Parameters
    ----------
    q : array_like, shape (V, N)
        Joint values of the visits in program order, rad (m).
    joints : sequence of int
        Joints whose angles may be turned by 2πk.
    lower, upper : array_like, shape (N,)
        Joint limits, rad.
    margin : array_like, shape (N,)
        Distance a turned angle keeps from the limits, rad.
    start, end : array_like, shape (N,), optional
        Fixed positions before the first and after the last visit (the home
        pose); None: the path starts (ends) at its first (last) visit.

    Returns
    -------
    ndarray, shape (V, N)
        The chosen angles; joints not in ``joints`` unchanged.

    Examples
    --------
    >>> out = shortest_turns([[3.0], [-3.0]], [0], [-7.0], [7.0], [0.0])
    >>> round(float(out[1, 0] - out[0, 0]), 4)  # −3 rad is 3.2832 rad, 0.2832 rad away
    0.2832
    """
    q = np.array(q, dtype=float)
    for j in joints:
        layers = [_equivalents(v, lower[j], upper[j], margin[j]) for v in q[:, j]]
        if not layers:
            continue
        cost = np.zeros(len(layers[0])) if start is None else np.abs(layers[0] - start[j])
        back = []
        for prev, layer in zip(layers[:-1], layers[1:]):
            total = cost[None, :] + np.abs(layer[:, None] - prev[None, :])
            back.append(np.argmin(total, axis=1))
            cost = total[np.arange(len(layer)), back[-1]]
        if end is not None:
            cost = cost + np.abs(layers[-1] - end[j])
        pick = int(np.argmin(cost))
        for i in range(len(layers) - 1, -1, -1):
            q[i, j] = layers[i][pick]
            if i > 0:
                pick = int(back[i - 1][pick])
    return q
