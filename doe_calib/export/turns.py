"""Equivalent angles of joints with more than one turn: q + 2πk chosen for short moves.

A revolute joint whose limits span more than one turn (a UR arm's ±360°) stands in the
same place at q and q ± 2π. For the fixed visiting order, each such joint's angle at
each visit is chosen among its equivalents, per joint and exactly, by dynamic
programming over the visits, for a lexicographic cost:

0. fewest moves across a value no path can pass (``blocked``);
1. least total **excess** Σ_i (|Δq_i| − d_i), d_i the shortest move any equivalent of
   visit i allows: every move as short as the limits let it be;
2. least total **travel** Σ_i |Δq_i|, start to end (the home pose).

The cost separates over the joints, so the optimum is exact. A later visit of a pose (its
loaded pass) keeps, where it can, the angle its first visit got: a visit on another turn
adds :data:`KEEP_TURN` to the excess, so the logged passes of a pose agree
(:mod:`doe_calib.io.logged_turns` accepts them either way) unless keeping the turn
costs more travel than that or crosses a blocked value; the first visits keep the
angles of the plain optimum. An equivalent other than
the design's angle keeps ``margin`` inside the limits and is used only on joints on
which the model's markers have period 2π (:func:`periodic_joints`: not a gear-ratio
error or a compliance by angle in bins).
"""
from __future__ import annotations

import numpy as np

from doe_calib.io.logged_turns import turn_joints
from doe_calib.io.measurements import Configurations
from doe_calib.model.evaluation import evaluate

TURN = 2.0 * np.pi
#: Largest difference of a marker's position a full turn away that counts as the same, m.
SAME_POSITION = 1e-9
#: Extra travel (rad) of a joint worth a later visit of a pose on its first visit's turn.
KEEP_TURN = np.pi / 2


def periodic_joints(model, joints, rng=None) -> tuple:
    """Those of ``joints`` on which ``model``'s marker positions have period 2π: checked at 8
    random configurations and parameter values (nominal ± 3 scales), one turn up and down."""
    rng = np.random.default_rng(0) if rng is None else rng
    robot = model.robot
    lower, upper = np.clip(robot.lower, -np.pi, None), np.clip(robot.upper, None, np.pi)
    q = rng.uniform(lower, upper, size=(8, robot.n_joints))
    wrench = rng.normal(0.0, 50.0, size=(8, 6))
    nominal = model.nominal()
    values = nominal.values + 3.0 * rng.standard_normal(len(nominal.values)) * np.array(
        [p.scale for p in nominal.parameters])
    here = evaluate(model.markers, Configurations.from_arrays(q, wrench), values)[0]

    def same(k, turn):
        moved = q.copy()
        moved[:, k] += turn
        there = evaluate(model.markers, Configurations.from_arrays(moved, wrench), values)[0]
        return bool(np.max(np.abs(there - here)) <= SAME_POSITION)

    return tuple(k for k in joints if same(k, TURN) and same(k, -TURN))


def blocked_turns(cm, robot) -> tuple:
    """Each multi-turn joint (0-based) with the values (rad) no path can pass in collision
    model ``cm`` (:func:`~doe_calib.collision.blocked_values`), for
    :attr:`.sequence.Plan.blocked`."""
    from doe_calib.collision import Workspace, blocked_values

    ws = Workspace(cm)
    found = ((j, blocked_values(cm, j, workspace=ws)) for j in turn_joints(robot))
    return tuple((j, tuple(float(v) for v in values)) for j, values in found if len(values))


def _equivalents(value: float, lower: float, upper: float, margin: float) -> np.ndarray:
    """``value`` and each ``value + 2πk`` at least ``margin`` inside [lower, upper]."""
    k = np.arange(-3, 4)
    shifted = value + TURN * k
    keep = (k == 0) | ((shifted >= lower + margin) & (shifted <= upper - margin))
    return shifted[keep]


def shortest_turns(q, joints, lower, upper, margin, start=None, end=None,
                   fixed=None, blocked=None, first=None) -> np.ndarray:
    """``q`` with each joint of ``joints`` turned by whole turns for short moves (module notes).

    Parameters
    ----------
    q : array_like, shape (V, N)
        Joint values of the visits in program order, rad (m).
    joints : sequence of int
        Joints whose angles may be turned by 2πk.
    lower, upper, margin : array_like, shape (N,)
        Joint limits and the distance a turned angle keeps from them, rad.
    start, end : array_like, shape (N,), optional
        Fixed positions before the first and after the last visit (None: none).
    fixed : array_like of bool, shape (V,), optional
        Rows passed through as they are (a load-change pose).
    blocked : dict, optional
        Joint → values (rad) no move of it may pass.
    first : array_like of int, shape (V,), optional
        The earlier visit of the same pose whose turn a visit keeps where that costs at most
        :data:`KEEP_TURN` (module notes); −1: none.

    Examples
    --------
    >>> out = shortest_turns([[3.0], [-3.0]], [0], [-7.0], [7.0], [0.0])
    >>> round(float(out[1, 0] - out[0, 0]), 4)  # −3 rad is 3.2832 rad, 0.2832 rad away
    0.2832
    """
    q = np.array(q, dtype=float)
    fixed = np.zeros(len(q), dtype=bool) if fixed is None else np.asarray(fixed, bool)
    first = np.full(len(q), -1) if first is None else np.asarray(first, int)
    for j in joints:
        layers = [np.array([v]) if keep else _equivalents(v, lower[j], upper[j], margin[j])
                  for v, keep in zip(q[:, j], fixed)]
        if not layers:
            continue
        ends = (None if start is None else start[j], None if end is None else end[j],
                np.zeros(0) if not blocked else np.asarray(blocked.get(j, ()), float))
        chosen = [layer[k] for layer, k in zip(layers, _best_path(layers, *ends))]
        if np.any(first >= 0):  # first visits as chosen; later ones on their turn if cheap
            kept = set(first[first >= 0].tolist())
            layers = [np.array([chosen[i]]) if i in kept else layer
                      for i, layer in enumerate(layers)]
            penalty = [np.where(np.isclose(layer, chosen[f]), 0.0, KEEP_TURN) if f >= 0 else
                       np.zeros(len(layer)) for layer, f in zip(layers, first)]
            chosen = [layer[k] for layer, k in zip(layers, _best_path(layers, *ends, penalty))]
        q[:, j] = chosen
    return q


def _step(prev, layer, blocked):
    """Travel, excess and crossings of a blocked value of each move prev[p] → layer[c],
    shape (C, P)."""
    travel = np.abs(layer[:, None] - prev[None, :])
    low, high = np.minimum(layer[:, None], prev[None, :]), np.maximum(layer[:, None], prev[None, :])
    crossed = ((blocked[None, None, :] > low[..., None]) &
               (blocked[None, None, :] < high[..., None])).any(axis=-1).astype(float)
    return travel, np.round(travel - travel.min(axis=0, keepdims=True), 9), crossed


def _best_path(layers, start, end, blocked, penalty=None) -> list:
    """Index into each layer of the path of least (crossings, excess, travel),
    lexicographically; ``penalty`` (one array per layer) adds to the excess of each option."""
    penalty = [np.zeros(len(layer)) for layer in layers] if penalty is None else penalty
    excess = penalty[0].copy()
    travel = np.zeros(len(layers[0]))
    crossings = np.zeros(len(layers[0]))
    if start is not None:
        travel, excess, crossings = (a[:, 0] for a in _step(np.array([start]), layers[0],
                                                             blocked))
        excess = excess + penalty[0]
    back = []
    for prev, layer, pen in zip(layers[:-1], layers[1:], penalty[1:]):
        t, e, x = _step(prev, layer, blocked)
        t, e, x = t + travel[None, :], e + excess[None, :] + pen[:, None], x + crossings[None, :]
        best = np.array([np.lexsort((t[c], e[c], x[c]))[0] for c in range(len(layer))])
        back.append(best)
        rows = np.arange(len(layer))
        travel, excess, crossings = t[rows, best], e[rows, best], x[rows, best]
    if end is not None:  # the last move, home: its excess over the nearest
        t, e, x = (a[0] for a in _step(layers[-1], np.array([end]), blocked))
        travel, excess, crossings = travel + t, excess + np.round(t - t.min(), 9), crossings + x
    pick = [int(np.lexsort((travel, np.round(excess, 9), crossings))[0])]
    for best in reversed(back):
        pick.append(int(best[pick[-1]]))
    return pick[::-1]
