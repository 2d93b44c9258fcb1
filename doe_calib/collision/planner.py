"""A joint-space motion planner for moves the straight line cannot clear: OMPL's RRT-Connect.

The state space is a joint box: first the box spanned by start and goal
widened by :data:`WIDEN` on each side, then, if no path is found there, the
whole joint range (the limits; ±2π for a continuous joint). A state is valid
when every checked pair keeps its move clearance
(:attr:`CollisionModel.move_margins`, :func:`.clearance.too_close`); OMPL
checks its motions at :data:`SEARCH_STEP` (Euclidean, hence on every joint).
The path found is shortened (:func:`_shorten`: OMPL's ``PathSimplifier``,
vertices removed until none can be, one deterministic rope shortcut, vertices
removed again: under half the state checks of ``simplifyMax``, which also
smooths by B-splines, and on the benchmark cell 7 % less joint travel), and
then every segment is checked again with :func:`.clearance.check_segment` at
≤ 1° steps — a path that fails that check is not returned (the next search is
made at 1°).

Planning is seeded (OMPL's global seed, set before each plan) and ends by
work, not by the clock: a search stops after :attr:`PlannerSettings.checks`
state validity checks (counted in the checker, evaluated by an
``ompl.base.PlannerTerminationCondition`` between the planner's iterations),
so the same seed gives the same path on any machine under any load. The wall
time :attr:`PlannerSettings.time` is only a safety net (30 s by default, far
beyond what the check budget takes); a search it ends is the only case whose
outcome depends on the machine.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from doe_calib.collision.clearance import SEGMENT_STEP, Workspace, check_path, too_close
from doe_calib.collision.hulls import first_too_close
from doe_calib.collision.passage import blocked_passage, joint_box
from doe_calib.io.setting_ranges import positive, whole

#: Joint step at which the search checks its motions, rad (the final check is at 1°).
SEARCH_STEP = np.radians(3.0)
#: Margin around the start–goal box searched first, rad (m).
WIDEN = np.pi / 2
#: Most rounds of vertex removal in each pass of :func:`_shorten`.
ROUNDS = 5


@dataclass(frozen=True)
class PlannerSettings:
    """How hard the planner tries.

    Attributes
    ----------
    time : float
        Safety net: wall time after which a search ends whatever its budget, s.
        Well above what ``checks`` takes (at most 0.1 ms a check), it never ends a
        search on a working machine; a search it ends is the only one whose
        outcome depends on the machine's speed and load.
    seed : int
        Seed of OMPL's random sampling.
    attempts : int
        Searches (seeds ``seed``, ``seed + 1``, …) in each of the two boxes
        (near start and goal, the whole joint range) before a move is given up.
    checks : int
        Work budget of one search: the state validity checks after which it
        ends without a path (25 µs each in the benchmark's UR5 cell, hulls tested
        first; 0.1 ms on the meshes alone). The searches of a measurement
        program take a hundred to a few thousand (one in the benchmark's UR5
        cell needs 3 000–5 000: what 1 s of wall time gave on a loaded machine).

    Raises
    ------
    OptionError
        ``time`` not positive, ``seed`` negative, ``attempts`` or ``checks`` below 1,
        or any of the three not a whole number.
    """

    time: float = 30.0
    seed: int = 0
    attempts: int = 1
    checks: int = 5000

    def __post_init__(self):
        positive("time", self.time, "s")
        whole("seed", self.seed, 0)
        whole("attempts", self.attempts, 1)
        whole("checks", self.checks, 1)


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


def _search(cm, qa, qb, lo, hi, margins, settings, seed, step, shorten, ws, memo):
    """One seeded RRT-Connect search, simplified unless not ``shorten``; the path's positions
    (K, N) or None.

    ``memo``: state (tuple of joint values) → whether it is free at ``margins``, kept
    between the searches of one move (a third of the states OMPL checks it has checked
    before: motions re-checked by the simplifier, the trees' connections)."""
    import pinocchio as pin
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

        ws.set_margins(margins)
        x = cm.configurations(qa)[:, 0]
        # each chain joint's index in the Pinocchio configuration, and whether it is (cos, sin)
        joints = [cm.model.joints[cm.model.getJointId(name)] for name in cm.joint_names]
        slots = [(jm.idx_q, jm.nq == 2) for jm in joints]
        done = [0]  # validity checks so far: the search's work

        def valid(state) -> bool:
            done[0] += 1  # a state checked before counts as work too: the same budget
            values = tuple(state[k] for k in range(n))
            known = memo.get(values)
            if known is not None:
                return known
            for (i, turns), v in zip(slots, values):
                if turns:
                    x[i], x[i + 1] = math.cos(v), math.sin(v)
                else:
                    x[i] = v
            if ws.hulls is not None:
                free = first_too_close(cm, ws, x) < 0
            else:
                free = not pin.computeCollisions(cm.model, ws.data, cm.geometry, ws.geometry, x,
                                                 True)
            memo[values] = free
            return free

        setup.setStateValidityChecker(valid)
        info = setup.getSpaceInformation()
        info.setStateValidityCheckingResolution(step / space.getMaximumExtent())
        start, goal = space.allocState(), space.allocState()
        for k in range(n):
            start[k], goal[k] = float(qa[k]), float(qb[k])
        setup.setStartAndGoalStates(start, goal)
        setup.setPlanner(og.RRTConnect(info))
        deadline = time.monotonic() + settings.time
        ptc = ob.PlannerTerminationCondition(
            lambda: done[0] >= settings.checks or time.monotonic() > deadline)
        solved = setup.solve(ptc)
        if not solved or not setup.haveExactSolutionPath():
            return None
        path = setup.getSolutionPath()
        if shorten:
            _shorten(og.PathSimplifier(info), path)
        out = np.array([[path.getState(i)[k] for k in range(n)]
                        for i in range(path.getStateCount())])
        setup.clear()
        return out
    finally:
        ou.setLogLevel(level)


def _shorten(simplifier, path) -> None:
    """Shorten an OMPL path in place, deterministically (seeded): vertices removed, a rope
    shortcut, vertices removed; every motion kept is checked at the search step."""
    for _ in range(ROUNDS):
        if not simplifier.reduceVertices(path):
            break
    simplifier.ropeShortcutPath(path)
    for _ in range(ROUNDS):
        if not simplifier.reduceVertices(path):
            break


def unplannable(cm, qa, qb, lower=None, upper=None, workspace: Workspace | None = None,
                prove: bool = True) -> bool:
    """Whether :func:`plan_move` gives up qa → qb (N,) before searching: an end closer than
    its move clearance, or (``prove``) a passage every path crosses proven blocked
    (:func:`.passage.blocked_passage`). Parameters as for :func:`plan_move`."""
    ws = Workspace(cm) if workspace is None else workspace
    qa, qb = np.asarray(qa, float), np.asarray(qb, float)
    margins = cm.move_margins or cm.margins
    if (too_close(cm, np.array([qa, qb]), margins, ws) >= 0).any():
        return True
    return prove and blocked_passage(cm, qa, qb, margins, *joint_box(cm, lower, upper),
                                     ws) is not None


def plan_move(cm, qa, qb, lower=None, upper=None, settings: PlannerSettings | None = None,
              workspace: Workspace | None = None, prove: bool = True,
              shorten: bool = True) -> PlannedMove | None:
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
    prove : bool
        First look for a proof that no path exists (:func:`.passage.blocked_passage`,
        milliseconds where a search that finds nothing spends its whole budget); False
        when the caller has looked already.
    shorten : bool
        Shorten the path found (:func:`_shorten`); False when only its existence matters
        (a reachability verdict): the search's raw path, still checked at ≤ 1° before it is
        returned. Planning the moves from home to the 28 poses of the benchmark's UR5 cell
        design that need a path, the shortening made 62 % of the state checks (38 800 of
        62 400) and half the time (11.2 s against 5.1 s CPU).

    Returns
    -------
    PlannedMove or None
        None when no path was found in ``settings.attempts`` searches (or a
        start or goal is not free, or no path exists).

    Examples
    --------
    >>> planned = plan_move(cm, qa, qb, robot.lower, robot.upper)  # doctest: +SKIP
    >>> [np.degrees(q).round(1) for q in planned.via]  # doctest: +SKIP
    """
    settings = PlannerSettings() if settings is None else settings
    ws = Workspace(cm) if workspace is None else workspace
    qa, qb = np.asarray(qa, float), np.asarray(qb, float)
    margins = cm.move_margins or cm.margins
    lo, hi = joint_box(cm, lower, upper)
    if unplannable(cm, qa, qb, lower, upper, ws, prove):
        return None
    near = (np.maximum(lo, np.minimum(qa, qb) - WIDEN), np.minimum(hi, np.maximum(qa, qb) + WIDEN))
    searches = [(near, SEARCH_STEP, settings.seed + a) for a in range(settings.attempts)]
    searches += [((lo, hi), SEGMENT_STEP, settings.seed + a) for a in range(settings.attempts)]
    memo = {}
    for (low, high), step, seed in searches:
        path = _search(cm, qa, qb, low, high, margins, settings, seed, step, shorten, ws, memo)
        if path is None:
            continue
        path[0], path[-1] = qa, qb
        hit, samples = check_path(cm, path, margins, ws)
        if hit is None:
            return PlannedMove(tuple(path[1:-1]), samples)
    return None
