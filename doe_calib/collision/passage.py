"""Blocked passages: a proof that no joint-space path joins two positions.

Any path from ``qa`` to ``qb`` inside the joint box passes, on each joint j,
every value between ``qa[j]`` and ``qb[j]``. When at one such value c every
position of the box with ``q[j] = c`` is too close on one checked pair, no path
exists: no route, no planner search, however long, can succeed, and none need
be tried. On a UR arm turned to +167° on its shoulder from +9°, the shoulder
must pass +90° — the upper arm pointing down into its table at every angle of
the base joint — where −193° (the same place, one turn away) would not.

A pair's distance depends only on the joints that move one of its bodies and
not the other (the nonzero entries of its row of
:func:`.bounds.motion_weights`). This module looks at the pairs that depend on
the joint j and on at most one other joint t: on the slab ``q[j] = c`` only t
changes the pair's distance, and t is swept over its range. The sweep covers
the range by intervals; at each interval's centre the pair is tested (coal's
collision test, as the planner's states are) at the margin
``m − W_t·w − SLACK``, with w the interval's half-width and W_t the pair's
closing rate per radian of t (:mod:`.bounds`): a pair closer than that at the
centre is closer than its margin m everywhere in the interval, since no point
of it moves by more than ``W_t·w`` there. An interval not proven is split
(:data:`SPLITS` times); a probe found free ends the sweep (that value of j can
be passed). A robot with a joint that is not revolute gets no bound and no
proof.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.collision.bounds import SLACK

#: Spacing of the values tried on a joint a path must pass, rad (a blocked stretch narrower
#: than this may go unproven: the planner then searches for the move as for any other).
VALUE_STEP = np.radians(5.0)
#: Positions of the swept joint tested at the move's margin before its sweep (any free: none).
PROBES = 8
#: Times an interval of a sweep not proven is halved before the value is given up.
SPLITS = 3
#: Most collision tests one sweep makes before it is given up.
MOST_TESTS = 4000


@dataclass(frozen=True)
class Blockage:
    """A joint value every path between two positions passes, where one pair is always too close.

    Attributes
    ----------
    joint : int
        The joint (0-based, chain order) the path must pass ``value`` on.
    value : float
        rad (m).
    pair : str
        The pair too close there, in words.
    margin : float
        The distance the pair must keep, m.
    swept : int or None
        The other joint the pair's distance depends on, proven over ``low`` … ``high``
        (rad); None when it depends on ``joint`` alone.
    low, high : float
    """

    joint: int
    value: float
    pair: str
    margin: float
    swept: int | None = None
    low: float = 0.0
    high: float = 0.0

    def words(self, joint_names, factors) -> str:
        """In words, values in display units (``factors``: deg or mm per rad or m)."""
        at = f"{joint_names[self.joint]} {self.value * factors[self.joint]:.1f}"
        where = "" if self.swept is None else (
            f" at every {joint_names[self.swept]} from {self.low * factors[self.swept]:.1f} "
            f"to {self.high * factors[self.swept]:.1f}")
        return (f"no path exists: every path passes {at}, where {self.pair} is closer than "
                f"{1000 * self.margin:g} mm{where}")


def blocked_passage(cm, qa, qb, margins=None, lower=None, upper=None,
                    workspace=None) -> Blockage | None:
    """A proof that no path qa → qb (N,) keeps ``margins``, or None when none is found.

    Parameters
    ----------
    cm : CollisionModel
    qa, qb : array_like, shape (N,)
        URDF values, rad (m).
    margins : float or sequence of float, optional
        Distance each pair keeps along the path, m; default the move margins
        (:attr:`CollisionModel.move_margins`).
    lower, upper : array_like, shape (N,), optional
        The joint box paths stay in, rad (default the collision model's; ±inf:
        ±2π, as the planner's), widened to hold ``qa`` and ``qb``.
    workspace : Workspace, optional

    Returns
    -------
    Blockage or None
        None also for a robot without a motion bound (a joint not revolute).
    """
    ws, weights, margins = _bounded(cm, margins, workspace)
    if weights is None:
        return None
    qa, qb = np.asarray(qa, float), np.asarray(qb, float)
    lo, hi = joint_box(cm, lower, upper)
    lo, hi = np.minimum(lo, np.minimum(qa, qb)), np.maximum(hi, np.maximum(qa, qb))
    for j in np.flatnonzero(np.abs(qb - qa) > 0):
        n = int(np.ceil(abs(qb[j] - qa[j]) / VALUE_STEP))
        values = qa[j] + (qb[j] - qa[j]) * np.arange(1, n + 1) / (n + 1)
        for k, m, t in _narrow_pairs(weights, margins, int(j)):
            found = _blocked_value(cm, ws, k, qa, int(j), values, m, t, lo, hi, weights[k])
            if found is not None:
                return Blockage(int(j), float(found), cm.pair_name(k), m, t,
                                0.0 if t is None else float(lo[t]),
                                0.0 if t is None else float(hi[t]))
    return None


def blocked_values(cm, joint: int, margins=None, lower=None, upper=None, workspace=None,
                   step: float = 2 * VALUE_STEP) -> np.ndarray:
    """Values of one joint no path may pass: one pair too close there at every position.

    The values of a grid over the joint's range (``step`` apart) where a pair whose distance
    depends on ``joint`` and at most one other joint is proven closer than its margin
    at every value of that other joint (module notes). A move of the joint across one
    of them can be made by no path; across none, nothing is said.

    Parameters
    ----------
    cm : CollisionModel
    joint : int
        0-based, chain order.
    margins, lower, upper, workspace
        As :func:`blocked_passage`.
    step : float
        Spacing of the values tried, rad.

    Returns
    -------
    ndarray
        The proven values, rad, ascending; empty for a robot without a motion bound.
    """
    ws, weights, margins = _bounded(cm, margins, workspace)
    if weights is None:
        return np.zeros(0)
    lo, hi = joint_box(cm, lower, upper)
    values = np.arange(lo[joint] + step / 2, hi[joint], step)
    base = np.zeros(len(lo))
    found = set()
    for k, m, t in _narrow_pairs(weights, margins, joint):
        left = np.array([v for v in values if v not in found])
        while len(left):
            c = _blocked_value(cm, ws, k, base, joint, left, m, t, lo, hi, weights[k])
            if c is None:
                break
            found.add(c)
            left = left[left > c]
    return np.array(sorted(found))


def _bounded(cm, margins, workspace):
    """(workspace, closing rates per pair and joint or None, each pair's margin, m)."""
    from doe_calib.collision.clearance import Workspace

    ws = Workspace(cm) if workspace is None else workspace
    n_pairs = len(cm.geometry.collisionPairs)
    weights = ws.motion(cm) if n_pairs else None
    margins = np.broadcast_to(np.asarray(cm.move_margins or cm.margins if margins is None
                                         else margins, float), n_pairs)
    return ws, weights, margins


def _narrow_pairs(weights, margins, joint: int):
    """(pair, its margin m, the one other joint t it depends on or None) of each pair whose
    distance depends on ``joint`` and at most one other, with room below m for coal's
    tolerance."""
    depends = weights > 0
    for k in np.flatnonzero(depends[:, joint] & (depends.sum(axis=1) <= 2)):
        if margins[k] - SLACK > 0:
            others = [int(t) for t in np.flatnonzero(depends[k]) if t != joint]
            yield int(k), float(margins[k]), (others[0] if others else None)


def joint_box(cm, lower, upper):
    """The joint box paths stay in, rad (m): the model's limits, ±2π where infinite."""
    lo = np.asarray(cm.lower if lower is None else lower, float)
    hi = np.asarray(cm.upper if upper is None else upper, float)
    return np.where(np.isfinite(lo), lo, -2 * np.pi), np.where(np.isfinite(hi), hi, 2 * np.pi)


def _blocked_value(cm, ws, k, base, j, values, m, t, lo, hi, w_k):
    """The first of ``values`` of joint j where pair k is closer than m at every value of
    joint t in [lo[t], hi[t]] (or at all, t None); None."""
    if t is None:
        q = np.repeat(base[None, :], len(values), axis=0)
        q[:, j] = values
        hit = _too_close(cm, ws, k, q, np.full(len(values), m - SLACK))
        found = np.flatnonzero(hit)
        return None if not len(found) else values[found[0]]
    alive = np.asarray(values, float)
    for probe in np.linspace(lo[t], hi[t], PROBES):  # cheap rejections first, all values at once
        q = np.repeat(base[None, :], len(alive), axis=0)
        q[:, j], q[:, t] = alive, probe
        alive = alive[_too_close(cm, ws, k, q, np.full(len(alive), m))]
        if not len(alive):
            return None
    for c in alive:
        if _covered(cm, ws, k, base, j, c, t, lo[t], hi[t], m, float(w_k[t])):
            return c
    return None


def _covered(cm, ws, k, base, j, c, t, low, high, m, rate) -> bool:
    """Whether pair k is closer than m at every q[t] in [low, high] with q[j] = c."""
    if rate <= 0:
        return False
    half = (m - SLACK) / (2 * rate)  # tested at m − rate·half − SLACK = (m − SLACK) / 2
    n = max(1, int(np.ceil((high - low) / (2 * half))))
    if n > MOST_TESTS:
        return False
    half = (high - low) / (2 * n)
    centres = low + half * (2 * np.arange(n) + 1)
    tests = 0
    for _ in range(SPLITS + 1):
        tests += len(centres)
        if tests > MOST_TESTS:
            return False
        q = np.repeat(base[None, :], len(centres), axis=0)
        q[:, j], q[:, t] = c, centres
        margin = m - rate * half - SLACK
        if margin < 0:
            return False
        left = centres[~_too_close(cm, ws, k, q, np.full(len(centres), margin))]
        if not len(left):
            return True
        half /= 2
        centres = np.concatenate([left - half, left + half])
    return False


def _too_close(cm, ws, k, q, margins) -> np.ndarray:
    """Whether pair k is closer than margins[i] at each position q[i] (M, N), rad (m)."""
    import pinocchio as pin

    request = ws.geometry.collisionRequests[k]
    kept = request.security_margin
    model, geometry, data, gdata = cm.model, cm.geometry, ws.data, ws.geometry
    out = np.zeros(len(q), bool)
    try:
        for i, x in enumerate(cm.configurations(q).T):
            request.security_margin = float(margins[i])
            pin.updateGeometryPlacements(model, data, geometry, gdata, x)
            out[i] = pin.computeCollision(geometry, gdata, k)
    finally:
        request.security_margin = kept
    return out
