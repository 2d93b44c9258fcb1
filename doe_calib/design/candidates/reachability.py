"""Poses a program can reach: a free path from the home pose, and the tracker's beams unblocked.

A designed pose is kept only when the robot can get there from its home
pose (the URDF zero clipped inside the joint bounds, or one given) without
a collision at the move clearance — straight in joint space, or along a path
the motion planner finds (:func:`doe_calib.collision.plan_move`) — and when
no body of the cell cuts the tracker's beam to any marker
(:func:`doe_calib.collision.blocked_beams`). Only the chosen poses are
checked: a rejected one is replaced from the candidates by the caller.

A joint with more than one turn of range reaches the same physical pose at
q ± 360°; a pose whose angles no free path joins to home (a UR shoulder at
280° lies beyond the table from 0°, at −80° it does not) is tried again at
its equivalent nearest home (:func:`nearest_equivalent`), which measures
exactly the same.

Only a path's existence matters here (the program plans its own moves), so
the poses already joined to home, and the via points of their paths, serve
as stepping stones: a straight move from one of the nearest, or a path planned
from the nearest and not shortened, joins a pose as surely as a path from home
and costs less. A pose is refused only where the planner's search from home
finds no path either, so every pose that search joins is joined; a pose it
misses (its budget spent, no proof that no path exists) may now be joined
too. On the benchmark's UR5 cell design from 20 000 candidates (47 chosen
poses checked, 2 with no path) this took the check from 15.3 s to 4.4 s CPU
with the same design; from 500 candidates one pose is now kept at its angles
as drawn, which the search from home had missed, instead of its equivalent
one turn away on four joints (the same physical pose: the criteria agree to
10 digits).
"""
from __future__ import annotations

import numpy as np

from doe_calib.collision import (Workspace, blocked_beams, check_segment, plan_move, too_close,
                                 unplannable)
from doe_calib.errors import OptionError, SolverError
from doe_calib.runtime.forked import forked_pool
from doe_calib.runtime.parallel import default_workers

#: Reason of a pose no free path joins to the home pose.
NO_PATH = "no free path from the home pose"
#: Positions already joined to home tried as the start of a straight move to a pose.
NEAREST = 3


def home_pose(robot, constraints, home=None) -> np.ndarray:
    """The home pose, rad (m): ``home`` if given (checked inside the bounds), else zero clipped.

    Parameters
    ----------
    robot : Robot
    constraints : DesignConstraints
        Its bounds (:meth:`DesignConstraints.bounds`, margin applied).
    home : array_like, shape (N,), optional
        URDF joint values, rad (m).

    Raises
    ------
    OptionError
        A ``home`` of the wrong length or outside the joint bounds, naming the joint.
    """
    lo, hi = constraints.bounds(robot)
    if home is None:
        return np.clip(np.zeros(robot.n_joints), lo, hi)
    home = np.asarray(home, float)
    if home.shape != (robot.n_joints,):
        raise OptionError(f"--home: {robot.n_joints} joint values expected, got {home.size}")
    for joint, v, a, b in zip(robot.joints, home, lo, hi):
        if not a - 1e-12 <= v <= b + 1e-12:
            f, unit = joint.display_factor, joint.display_unit
            raise OptionError(f"--home: joint {joint.name} = {v * f:.6g} {unit} is outside "
                              f"[{a * f:.6g}, {b * f:.6g}] {unit} (the joint limits, margin "
                              f"applied)")
    return home


def free_home(collision, home, robot, given: bool, candidates) -> tuple:
    """The home pose checked free at the move clearance, and the pair when it was replaced.

    A given home (``--home``) that is not free is an error; the default one
    (the URDF zero, e.g. a UR's wrist hanging below the base plane) is then
    replaced by the free candidate pose nearest to it.

    Returns
    -------
    (ndarray, str)
        The home pose, rad (m), and "" or the pair too close at the one asked for.
    """
    hit = too_close(collision, np.atleast_2d(home), collision.move_margins or None)[0]
    if hit < 0:
        return np.asarray(home, float), ""
    deg = ", ".join(f"{v:.6g}" for v in np.asarray(home) * robot.display_factors)
    if given or not len(candidates):
        raise OptionError(f"the home pose ({deg}) is itself too close: "
                          f"{collision.pair_name(int(hit))}; give a free one with --home")
    near = candidates[int(np.argmin(np.linalg.norm(candidates - home, axis=1)))]
    return near, collision.pair_name(int(hit))


def nearest_equivalent(q, home, robot, lower, upper) -> np.ndarray:
    """q (N,) with each revolute joint turned by whole turns to lie nearest ``home``, in bounds."""
    q = np.asarray(q, float)
    turned = q + 2 * np.pi * np.round((np.asarray(home) - q) / (2 * np.pi))
    ok = np.array([j.kind != "prismatic" for j in robot.joints]) \
        & (turned >= np.asarray(lower) - 1e-12) & (turned <= np.asarray(upper) + 1e-12)
    return np.where(ok, turned, q)


def unreachable(collision, q, home, robot, lower, upper, workers: int | None = None,
                joined: list | None = None) -> list:
    """For each pose of q (M, N), why a program cannot use it, or the angles it is reached at.

    Each pose is looked at first on its own (its beams, the straight move from
    ``home``: :func:`_looked_at`), in ``workers`` processes (this one among them);
    then the poses left are joined in order by :func:`_planned`, each from the
    nearest position already joined to ``home`` — a pose joined before it or a via
    point of its path — before a path from ``home`` itself is planned, while the
    other processes look for the proof that no path from ``home`` exists
    (:func:`_plannable`) for the poses to come.
    Every path so found is free (each move checked at ≤ 1°); a pose is refused only
    where the planner's own search from ``home`` finds no path either.

    Parameters
    ----------
    lower, upper : array_like, shape (N,)
        Joint bounds an equivalent angle must stay in, rad (m).
    workers : int, optional
        Processes looking at the poses at once when the collision model plans, this one
        and ``workers - 1`` forked ones (:func:`~doe_calib.runtime.forked.forked_pool`;
        default the CPUs; 1: this one alone). Each pose's look and proof are its own and
        the paths are planned in this process, in order: the result does not depend on it.
    joined : list of ndarray, optional
        Positions (N,) already joined to ``home`` (by an earlier call), rad (m), used as
        stepping stones too; it gains the positions this call joins.

    Returns
    -------
    list of (str or None, ndarray)
        Per pose: the reason — ``"line of sight: blocked by <body>"`` when a
        beam to a marker is blocked, :data:`NO_PATH` when neither the
        straight move from ``home`` nor a planned path (the collision model's
        :attr:`~doe_calib.collision.CollisionModel.planner`) is free at the
        move clearance, at the pose's angles or at their equivalent nearest
        home —, or None; and the angles to use (the equivalent when only it
        is joined).
    """
    q = np.atleast_2d(q)
    shared = (collision, q, home, robot, lower, upper, Workspace(collision))  # a copy per worker
    workers = default_workers() if workers is None else max(1, int(workers))
    # without a planner every pose is a straight check: not worth the processes
    if collision.planner is None or len(q) < 2:
        workers = 1
    with forked_pool(shared, workers - 1) as results:
        # this process is one of the workers: it looks at its share of the poses meanwhile
        theirs = results(_looked_at, [i for i in range(len(q)) if i % workers])
        looked = [_looked_at(shared, i) if i % workers == 0 else None for i in range(len(q))]
        looked = [next(theirs) if look is None else look for look in looked]
        joined = [] if joined is None else joined
        joined += [used for why, used, _ in looked if why is None]  # straight from home
        proven = results(_plannable, [tried for _, _, tried in looked if tried])
        ws, out = Workspace(collision), []
        for why, used, tried in looked:
            left = next(proven) if tried else []
            planned = next((t for t in left if _planned(collision, home, t, joined, ws)), None)
            out.append((why, used) if planned is None else (None, planned))
    return out


def revert_unreachable(collision, q, start, home, robot, constraints) -> tuple:
    """Poses q (M, N) at the angles they are reached at from ``home``, each unreachable one
    back at its ``start`` (M, N), rad (m); and how many went back. ``constraints``: the
    :class:`DesignConstraints` whose bounds the equivalent angles stay in."""
    checked = unreachable(collision, q, home, robot, *constraints.bounds(robot))
    back = np.array([why is not None for why, _ in checked])
    return np.where(back[:, None], start, [used for _, used in checked]), int(back.sum())


def _looked_at(shared, i: int):
    """Pose i of :func:`unreachable` on its own: (reason or None, the angles used, the angles
    whose straight move from home is not free, in order, when a path may join them)."""
    collision, q, home, robot, lower, upper, ws = shared
    pose = q[i]
    blocked = blocked_beams(collision, pose, ws)
    if blocked:
        return f"line of sight: blocked by {blocked[0].body}", pose, []
    near = nearest_equivalent(pose, home, robot, lower, upper)
    tried, plans = [], collision.planner is not None
    for t in [pose] + ([near] if not np.allclose(near, pose) else []):
        if check_segment(collision, home, t, collision.move_margins or None, workspace=ws).free:
            # a path joining the angles tried before is still preferred: they are the pose's own
            return None, t, tried
        if plans:
            tried.append(t)
    return NO_PATH, pose, tried


def _plannable(shared, tried: list) -> list:
    """The angles of ``tried`` (:func:`_looked_at`) a path from home may join: those the
    planner would not give up before searching (:func:`~doe_calib.collision.unplannable`)."""
    collision, home, ws = shared[0], shared[2], shared[6]
    return [t for t in tried if not unplannable(collision, home, t, workspace=ws)]


def _planned(collision, home, pose, joined, ws) -> bool:
    """Whether a planned free path joins ``home`` to ``pose`` (N,).

    Tried in turn: a straight move from each of the :data:`NEAREST` positions of
    ``joined`` (each joined to ``home`` already) nearest the pose; a path planned
    from the nearest, not shortened (only its existence matters); a path planned
    from ``home``, as without stepping stones. ``joined`` gains the pose and the via
    points of its path.
    """
    settings, margins = collision.planner, collision.move_margins or None
    path = None
    if joined:
        known = np.asarray(joined)
        nearest = known[np.argsort(np.max(np.abs(known - pose), axis=1), kind="stable")]
        if any(check_segment(collision, h, pose, margins, workspace=ws).free
               for h in nearest[:NEAREST]):
            joined.append(pose)
            return True
        path = plan_move(collision, nearest[0], pose, settings=settings, workspace=ws,
                         shorten=False)
    if path is None:
        path = plan_move(collision, home, pose, settings=settings, workspace=ws, prove=False)
    if path is not None:
        joined.extend([*path.via, pose])
    return path is not None


def reachable_choice(choose, q, pose_of, collision, home, robot, lower, upper,
                     rounds: int = 8) -> tuple:
    """The candidates ``choose`` picks once every chosen pose is joined to ``home``.

    An unreachable chosen pose (:func:`unreachable`) is removed, with all its
    variants, and ``choose`` asked again, at most ``rounds`` times. Each choice's
    new poses are checked with the stepping stones the checks before found (on the
    benchmark's UR5 cell from 20 000 candidates, the second check's 17 poses need 4
    planned paths instead of 7: 0.36 → 0.28 s CPU, the same design).

    Parameters
    ----------
    choose : callable(allowed) -> ndarray of int
        Candidate indices chosen among the candidates whose pose is ``allowed``
        (bool mask over the poses, shape (P,)).
    q : ndarray, shape (P, N)
        The candidate poses, rad (m).
    pose_of : ndarray of int, shape (K,)
        The pose (row of ``q``) of each candidate.
    collision, home, robot, lower, upper :
        As for :func:`unreachable`.

    Returns
    -------
    (ndarray, ndarray, dict)
        The chosen candidates; ``q`` with each checked pose at the angles it is
        reached at; reason → how many chosen poses were replaced for it.

    Raises
    ------
    SolverError
        When too few reachable poses are left, or some are still unreachable
        after ``rounds`` choices.
    """
    allowed, verdict, used, replaced = np.ones(len(q), bool), {}, np.array(q, float), {}
    joined = []  # the stepping stones every choice's check has found
    for _ in range(rounds):
        chosen = np.asarray(choose(allowed))
        poses = [int(k) for k in np.asarray(pose_of)[chosen]]
        todo = [k for k in dict.fromkeys(poses) if k not in verdict]
        for k, (why, angles) in zip(todo, unreachable(collision, q[todo], home, robot, lower,
                                                      upper, joined=joined)):
            verdict[k], used[k] = why, angles
        bad = [k for k in poses if verdict[k] is not None]
        if not bad:
            return chosen, used, replaced
        for k in bad:
            allowed[k] = False
            replaced[verdict[k]] = replaced.get(verdict[k], 0) + 1
    raise SolverError(f"after {rounds} choices some chosen poses are still unreachable: "
                      + ", ".join(f"{n} {why}" for why, n in replaced.items())
                      + "; give more candidates, another --home or fewer constraints")
