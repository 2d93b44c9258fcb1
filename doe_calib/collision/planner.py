"""A joint-space motion planner for moves the straight line cannot clear: OMPL's RRT-Connect.

The state space is the chain's joint box (the URDF limits; ±2π for a
continuous joint); a state is valid when every checked pair keeps its move
clearance (:attr:`CollisionModel.move_margins`, :func:`.clearance.too_close`);
OMPL checks its motions at ≤ 1° (Euclidean, hence on every joint). The path
found is shortened and smoothed (``PathSimplifier``: vertices removed,
shortcuts), and then every segment is checked again with
:func:`.clearance.check_segment` at ≤ 1° steps — a path that fails that check
is not returned.

Planning is seeded (OMPL's global seed, set before each plan) and bounded in
time (:attr:`PlannerSettings.time`): the same seed gives the same path as
long as the search ends before the time bound, which the small searches of a
measurement program do (a few hundred states, well under a second).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.collision.clearance import SEGMENT_STEP, Workspace, check_segment, too_close


@dataclass(frozen=True)
class PlannerSettings:
    """How hard the planner tries.

    Attributes
    ----------
    time : float
        Longest search for one move, s.
    simplify_time : float
        Longest shortening and smoothing of a path found, s.
    seed : int
        Seed of OMPL's random sampling.
    attempts : int
        Searches (seeds ``seed``, ``seed + 1``, …) before a move is given up.
    """

    time: float = 2.0
    simplify_time: float = 0.5
    seed: int = 0
    attempts: int = 2


@dataclass(frozen=True)
class PlannedMove:
    """A collision-free path between two positions.

    Attributes
    ----------
    via : tuple of ndarray, shape (N,) each
        Intermediate positions, URDF values rad (m), both ends excluded.
    samples : int
        Poses checked along the final path at ≤ 1° steps.
    """

    via: tuple
    samples: int


def _bounds(lower, upper):
    lo = np.where(np.isfinite(lower), lower, -2 * np.pi)
    hi = np.where(np.isfinite(upper), upper, 2 * np.pi)
    return lo, hi


def _search(cm, qa, qb, lo, hi, margins, settings, seed, ws):
    """One seeded RRT-Connect search, simplified; the path's positions (K, N) or None."""
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    n = len(qa)
    level = ou.getLogLevel()
    ou.setLogLevel(ou.LOG_NONE)  # OMPL says re-seeding is not deterministic; it is, from here
    try:
        ou.RNG.setSeed(int(seed) + 1)
        space = ob.RealVectorStateSpace(n)
        bounds = ob.RealVectorBounds(n)
        for k in range(n):
            bounds.setLow(k, float(lo[k]))
            bounds.setHigh(k, float(hi[k]))
        space.setBounds(bounds)
        setup = og.SimpleSetup(space)

        def valid(state) -> bool:
            q = np.array([state[k] for k in range(n)])
            return bool(too_close(cm, q[None], margins, ws)[0] < 0)

        setup.setStateValidityChecker(valid)
        info = setup.getSpaceInformation()
        info.setStateValidityCheckingResolution(SEGMENT_STEP / space.getMaximumExtent())
        start, goal = space.allocState(), space.allocState()
        for k in range(n):
            start[k], goal[k] = float(qa[k]), float(qb[k])
        setup.setStartAndGoalStates(start, goal)
        setup.setPlanner(og.RRTConnect(info))
        solved = setup.solve(settings.time)
        if not solved or not setup.haveExactSolutionPath():
            return None
        setup.simplifySolution(settings.simplify_time)
        path = setup.getSolutionPath()
        out = np.array([[path.getState(i)[k] for k in range(n)]
                        for i in range(path.getStateCount())])
        setup.clear()
        return out
    finally:
        ou.setLogLevel(level)


def plan_move(cm, qa, qb, lower=None, upper=None, settings: PlannerSettings | None = None,
              workspace: Workspace | None = None) -> PlannedMove | None:
    """A collision-free joint-space path qa → qb (N,) at the move clearance, or None.

    Parameters
    ----------
    cm : CollisionModel
    qa, qb : array_like, shape (N,)
        Start and goal, URDF values rad (m); both must keep the move clearance.
    lower, upper : array_like, shape (N,), optional
        Joint limits the path stays inside, rad (m); ±inf: ±2π. Default the
        collision model's (:attr:`CollisionModel.lower`, ``upper``).
    settings : PlannerSettings, optional

    Returns
    -------
    PlannedMove or None
        None when no path was found in ``settings.attempts`` searches (or a
        start or goal is not free).

    Examples
    --------
    >>> planned = plan_move(cm, qa, qb, robot.lower, robot.upper)  # doctest: +SKIP
    >>> [np.degrees(q).round(1) for q in planned.via]  # doctest: +SKIP
    """
    settings = PlannerSettings() if settings is None else settings
    ws = Workspace(cm) if workspace is None else workspace
    qa, qb = np.asarray(qa, float), np.asarray(qb, float)
    margins = cm.move_margins or cm.margins
    lo, hi = _bounds(np.asarray(cm.lower if lower is None else lower, float),
                     np.asarray(cm.upper if upper is None else upper, float))
    if (too_close(cm, np.array([qa, qb]), margins, ws) >= 0).any():
        return None
    for attempt in range(settings.attempts):
        path = _search(cm, qa, qb, lo, hi, margins, settings, settings.seed + attempt, ws)
        if path is None:
            continue
        path[0], path[-1] = qa, qb
        samples, free = 0, True
        for a, b in zip(path[:-1], path[1:]):
            check = check_segment(cm, a, b, margins, workspace=ws)
            samples += check.samples
            if not check.free:
                free = False
                break
        if free:
            return PlannedMove(tuple(path[1:-1]), samples)
    return None
