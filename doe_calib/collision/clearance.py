"""Clearance at a pose, collision screening of many poses, and the check of a joint-space move.

Screening asks coal only whether each checked pair is closer than the
clearance (a collision test with a security margin, stopping at the first
pair: cheap), on the links' convex hulls first and on their meshes only where
the hulls are too close (:mod:`.hulls`); distances, which cost more, are
computed only for the poses whose clearance is reported.

A move is checked at every pose of its ≤ 1° grid, but a pair is tested only
where it may be too close: the collision test that finds a pair clear (on its
hulls or on its meshes) also bounds its distance, and :mod:`.bounds` bounds how
fast a joint step can close it, so the poses before that bound is used up are
skipped for that pair. The first pose found too close and its pair are those
the test of every pair at every pose finds (the argument is in :mod:`.bounds`);
the count of poses checked is the grid's.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from doe_calib.collision.bounds import SLACK, motion_weights
from doe_calib.collision.hulls import HULL_SLACK, first_too_close

#: Largest joint step between the checked samples of a move, rad (m for prismatic joints).
SEGMENT_STEP = np.radians(1.0)


@dataclass(frozen=True)
class Clearance:
    """The pair closest to its required distance at one pose.

    Attributes
    ----------
    distance : float
        Its distance, m; ≤ 0 when the pair touches or overlaps.
    pair : str
        In words, ``"forearm_link vs marker A"``.
    required : float
        The distance it must keep, m (the clearance; the self-clearance
        between two links of the robot).
    """

    distance: float
    pair: str
    required: float = 0.0

    @property
    def free(self) -> bool:
        """Whether the pair keeps its required distance (then every checked pair does)."""
        return self.distance >= self.required

    @property
    def mm(self) -> float:
        return 1000.0 * self.distance


@dataclass(frozen=True)
class SegmentCheck:
    """A move from ``qa`` to ``qb`` checked at joint steps of at most :data:`SEGMENT_STEP`.

    Attributes
    ----------
    samples : int
        Poses checked, both ends included.
    first : float or None
        Fraction of the move (0 … 1) at the first pose closer than the margin; None when free.
    pair : str or None
        The pair found too close there.
    """

    samples: int
    first: float | None
    pair: str | None

    @property
    def free(self) -> bool:
        return self.first is None


class Workspace:
    """Scratch for one thread: Pinocchio data and geometry data of a collision model.

    Create one per thread with ``Workspace(cm)`` and pass it to the functions
    of this module; they create a fresh one when none is given.

    Parameters
    ----------
    cm : CollisionModel
    bounded : bool
        Let :func:`check_segment` skip the poses where a pair is proven clear
        (default); False: test every pair at every pose of every move (the
        reference the benchmarks and tests compare with: the same answers,
        slower).
    hulls : bool
        Test a pose's pairs on their convex hulls first and on their meshes only
        where the hulls are too close (:mod:`.hulls`; default, when the model has
        meshes); False: on their meshes (the reference the benchmarks and tests
        compare with: the same answers, slower).
    """

    def __init__(self, cm, bounded: bool = True, hulls: bool = True):
        self.data = cm.model.createData()
        self.geometry = cm.geometry.createData()
        self.margins = None
        # held references into the geometry data's results (indexing it copies each one)
        self.results = list(self.geometry.collisionResults)
        self.hulls = cm.hulls.createData() if hulls and cm.hulls is not None else None
        self.hull_results = () if self.hulls is None else list(self.hulls.collisionResults)
        self.bounded = bounded
        self._motion = False  # not computed yet
        self.sight = None  # what the tracker's beams are checked against (.beams, computed once)

    def motion(self, cm) -> np.ndarray | None:
        """Per pair and joint, how fast the pair can close (:func:`.bounds.motion_weights`,
        computed once)."""
        if self._motion is False:
            self._motion = motion_weights(cm.model, cm.geometry, cm.joint_names)
        return self._motion

    def set_margins(self, margins) -> None:
        """Make the collision tests report each pair closer than its margin (m; one for all)."""
        margins = tuple(float(m) for m in np.broadcast_to(np.asarray(margins, float),
                                                          len(self.results)))
        if margins != self.margins:
            for request, m in zip(self.geometry.collisionRequests, margins):
                request.security_margin = m
            if self.hulls is not None:
                for request, m in zip(self.hulls.collisionRequests, margins):
                    request.security_margin = m + HULL_SLACK
            self.margins = margins


def clearance(cm, q, workspace: Workspace | None = None) -> Clearance:
    """The pair with the least distance to spare at pose q (N,), rad/m: its distance and name.

    Every checked pair keeps its required distance when the returned one does.
    Pairs whose distance never changes (:attr:`CollisionModel.fixed`) are not
    reported unless they are the only ones or closer than required.

    Examples
    --------
    >>> from doe_calib import Robot, Tool, examples
    >>> from doe_calib.collision import build_collision_model
    >>> cm = build_collision_model(Robot.from_urdf(examples.ROBOT_URDF),
    ...                            Tool.from_yaml(examples.TOOL_YAML))
    >>> clearance(cm, [0, -1.57, 1.57, 0, 0.5, 0]).mm > 20
    True
    """
    import pinocchio as pin

    ws = Workspace(cm) if workspace is None else workspace
    if not len(cm.geometry.collisionPairs):
        return Clearance(float("inf"), "no pair checked")
    pin.computeDistances(cm.model, ws.data, cm.geometry, ws.geometry,
                         cm.configurations(q)[:, 0])
    d = np.array([r.min_distance for r in ws.geometry.distanceResults])
    spare = d - np.asarray(cm.margins)
    fixed = np.zeros(len(d), bool) if len(cm.fixed) != len(d) else np.array(cm.fixed)
    if (~fixed).any() and not (spare[fixed] < 0).any():
        spare = np.where(fixed, np.inf, spare)
    k = int(np.argmin(spare))
    return Clearance(float(d[k]), cm.pair_name(k), float(cm.margins[k]))


def too_close(cm, q, margin: float | None = None, workspace: Workspace | None = None):
    """For each pose of q (M, N), the first checked pair closer than ``margin``; −1 when none.

    Parameters
    ----------
    margin : float or sequence of float, optional
        Distance every pair (or each pair) must keep, m; default each pair's
        (:attr:`CollisionModel.margins`); a move's are
        :attr:`CollisionModel.move_margins`.

    Returns
    -------
    ndarray of int, shape (M,)
        Index of the pair (:meth:`CollisionModel.pair_name`), or −1.
    """
    import pinocchio as pin

    ws = Workspace(cm) if workspace is None else workspace
    ws.set_margins(cm.margins if margin is None else margin)
    configurations = cm.configurations(q)
    out = np.full(configurations.shape[1], -1)
    if ws.hulls is not None:
        for i, x in enumerate(configurations.T):
            out[i] = first_too_close(cm, ws, x)
        return out
    results = ws.geometry.collisionResults
    for i, x in enumerate(configurations.T):
        if pin.computeCollisions(cm.model, ws.data, cm.geometry, ws.geometry, x, True):
            # pairs are tested in order and the test stops at the first one touching
            out[i] = next(k for k, r in enumerate(results) if r.isCollision())
    return out


def contacts(cm, q, workspace: Workspace | None = None) -> tuple:
    """Every checked pair closer than its required distance at pose q (N,), in words."""
    import pinocchio as pin

    ws = Workspace(cm) if workspace is None else workspace
    ws.set_margins(cm.margins)
    pin.computeCollisions(cm.model, ws.data, cm.geometry, ws.geometry,
                          cm.configurations(q)[:, 0], False)
    return tuple(cm.pair_name(k) for k, r in enumerate(ws.geometry.collisionResults)
                 if r.isCollision())


def check_segment(cm, qa, qb, margin: float | None = None, step: float = SEGMENT_STEP,
                  workspace: Workspace | None = None, pairs=None) -> SegmentCheck:
    """Check the straight joint-space move qa → qb (N,) at joint steps of at most ``step``.

    Parameters
    ----------
    margin : float or sequence of float, optional
        Distance every pair (or each pair) keeps along the move, m; default
        each pair's pose clearance (:attr:`CollisionModel.margins`).
    step : float
        Largest change of any joint between checked poses, rad (m).
    pairs : sequence of int, optional
        Check only these pairs (indices, :meth:`CollisionModel.pair_name`), in
        this order: a quick look for a collision already suspected (a move
        that collides on them collides); default every checked pair.
    """
    qa, qb = np.asarray(qa, float), np.asarray(qb, float)
    ws = Workspace(cm) if workspace is None else workspace
    t = np.linspace(0.0, 1.0, max(2, int(np.ceil(np.max(np.abs(qb - qa)) / step)) + 1))
    weights = ws.motion(cm) if ws.bounded else None
    if pairs is None and (weights is None or not len(cm.geometry.collisionPairs)):
        hit = too_close(cm, qa + t[:, None] * (qb - qa), margin, ws)
        bad = np.flatnonzero(hit >= 0)
        found = (bad[0], int(hit[bad[0]])) if len(bad) else None
    else:
        pairs = None if pairs is None else tuple(int(k) for k in pairs)
        found = _first_too_close(cm, qa, qb, t, margin, weights, ws, pairs)
    if found is None:
        return SegmentCheck(len(t), None, None)
    return SegmentCheck(len(t), float(t[found[0]]), cm.pair_name(found[1]))


def check_path(cm, path, margin=None, workspace: Workspace | None = None,
               pairs=None) -> tuple:
    """The first move of ``path`` (positions, rad/m) that collides, checked move by move.

    Parameters are those of :func:`check_segment` (at its step).

    Returns
    -------
    (SegmentCheck or None, int)
        The first colliding move's check (None: every move is free) and the poses
        checked up to it.
    """
    samples = 0
    for qa, qb in zip(path[:-1], path[1:]):
        check = check_segment(cm, qa, qb, margin, workspace=workspace, pairs=pairs)
        samples += check.samples
        if not check.free:
            return check, samples
    return None, samples


def _first_too_close(cm, qa, qb, t, margin, weights, ws, pairs=None):
    """(pose index, pair index) of the first pose of qa + t (qb − qa) a pair is too close at.

    Each pair is tested at a pose only when the bound from its last test
    (:mod:`.bounds`) no longer proves it clear there; None when every pose is free.
    The pairs due at a pose are tested in checking order, so the pair returned is
    the first one the test of every pair finds. ``pairs``: only these (indices, in
    this order; weights None: each at every pose). With hulls (:mod:`.hulls`), a
    pair is tested on its meshes only where its hulls are too close; a hull test
    that clears it gives the bound.
    """
    import pinocchio as pin

    ws.set_margins(cm.margins if margin is None else margin)
    poses = np.ascontiguousarray(cm.configurations(qa + t[:, None] * (qb - qa)).T)
    n = len(t)
    order = range(len(cm.geometry.collisionPairs)) if pairs is None else pairs
    # the largest closing of each pair between neighbouring poses, m (the grid is uniform)
    rates = None if weights is None else weights if pairs is None else weights[list(pairs)]
    per_step = [math.inf] * len(order) if rates is None else \
        ((rates @ np.abs(qb - qa)) / (n - 1)).tolist()
    due = [0] * len(per_step)
    results, hull_results = ws.results, ws.hull_results
    model, geometry, data, gdata = cm.model, cm.geometry, ws.data, ws.geometry
    hulls, hdata = cm.hulls, ws.hulls
    collide, place, finite = pin.computeCollision, pin.updateGeometryPlacements, math.isfinite
    i = 0
    while i < n:
        placed = hdata is None  # the meshes are placed only when a hull test flags a pair
        place(model, data, geometry if placed else hulls, gdata if placed else hdata, poses[i])
        following = n
        for slot, when in enumerate(due):
            if when <= i:
                k = order[slot]
                if hdata is not None and not collide(hulls, hdata, k):
                    # the hulls' bound, on their distance less (margin + HULL_SLACK), is
                    # below the meshes' distance less the margin
                    spare = hull_results[k].distance_lower_bound - SLACK
                else:
                    if not placed:
                        place(model, data, geometry, gdata)
                        placed = True
                    if collide(geometry, gdata, k):
                        return i, k
                    # coal's bound is on the distance less the margin (the distance to a
                    # collision): clear while the closing since this pose stays below it
                    spare = results[k].distance_lower_bound - SLACK
                skip = 0
                if spare > 0 and finite(spare):
                    rate = per_step[slot]
                    skip = n if rate <= 0 else min(n, int(spare / rate))
                when = due[slot] = i + 1 + skip
            if when < following:
                following = when
        i = following
    return None
