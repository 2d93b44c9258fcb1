"""Candidate poses: random joint angles inside the bounds that satisfy every constraint."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.collision import Workspace, screen_beams, too_close
from doe_calib.design.result import CandidateCount
from doe_calib.errors import SolverError
from doe_calib.runtime.forked import forked_map

_MAX_DRAWS = 50  # draw at most this many poses per candidate wanted
_SHARE = 2000  # fewest poses screened by one process
_SHARES = 8  # most shares the poses of one round are screened in
# fewest drawn poses judged by one process: with a collision model (~20 µs each in the UR5
# cell, most of it screening the feasible ones), and without (~3 µs each; forking costs ~20 ms)
_DRAWN_SHARE = 2000
_DRAWN_SHARE_FREE = 20000


@dataclass(frozen=True, eq=False)
class CandidateSet:
    """Feasible candidate poses and what the constraints removed to get them.

    Attributes
    ----------
    q : ndarray, shape (K, N)
        Candidate poses, rad/m.
    drawn : int
        Poses drawn uniformly inside the joint bounds (margin applied).
    removed : dict
        Constraint name → number of drawn poses violating it (a pose may
        violate several).
    names : tuple of str
        Pose id of each candidate when they come from a file
        (:mod:`.from_file`); empty for random candidates.
    source : str
        The file they come from ("" for random candidates).
    """

    q: np.ndarray
    drawn: int
    removed: dict
    names: tuple = ()
    source: str = ""

    def count(self) -> CandidateCount:
        """How many were drawn, kept and removed by which constraint."""
        return CandidateCount(self.drawn, len(self.q), dict(self.removed), source=self.source)


def feasible_candidates(feasibility, robot, n: int, rng, collision=None,
                        workers: int | None = None) -> CandidateSet:
    """``n`` poses drawn uniformly inside the bounds and kept if feasible.

    Draws in rounds sized by the acceptance rate so far, up to
    ``50 n`` poses in all. With a :class:`~doe_calib.collision.CollisionModel`,
    the poses meeting every other constraint are also screened for pairs
    closer than their clearance; each rejected pose is counted under the
    first such pair (``"collision: upper_arm_link vs floor"``). When the
    collision model has a tracker, the poses left whose beam to a marker is
    blocked are counted under the body blocking it
    (``"line of sight: blocked by forearm_link"``). Each round is judged in
    forked processes (:func:`judge`; ``workers``: default the CPUs, 1: in this
    process); the candidates and the counts do not depend on them.

    Raises
    ------
    SolverError
        When no drawn pose is feasible, or too few coverage bins hold candidates.
    """
    constraints = feasibility.constraints
    lo, hi = constraints.bounds(robot)
    kept, drawn, removed = [], 0, {}
    batch = n
    workspace = None if collision is None else Workspace(collision)
    while sum(len(k) for k in kept) < n and drawn < _MAX_DRAWS * n:
        q = rng.uniform(lo, hi, (batch, robot.n_joints))
        ok, violated = judge(feasibility, q, collision, workspace, workers)
        kept.append(q[ok])
        drawn += batch
        for name, v in violated.items():
            removed[name] = removed.get(name, 0) + int(v.sum())
        have = sum(len(k) for k in kept)
        rate = max(have / drawn, 1.0 / _MAX_DRAWS)
        batch = min(int(np.ceil(1.1 * (n - have) / rate)) + 16, _MAX_DRAWS * n - drawn)
    q = np.concatenate(kept)[:n]
    if len(q) == 0:
        worst = max(removed, key=removed.get)
        raise SolverError(f"none of {drawn} random poses satisfies the constraints "
                          f"({constraints.source or 'defaults'}"
                          f"{'' if collision is None else ', collisions'}); {worst} removed "
                          f"{removed[worst]}, the most of any")
    cov = constraints.coverage
    if cov is not None and len(cov.used(q)) < cov.min_bins:
        raise SolverError(f"coverage asks for {cov.min_bins} bins of joint "
                          f"{robot.joints[cov.joint].name}, but feasible candidates fall in only "
                          f"{len(cov.used(q))}: {cov.used(q)}")
    return CandidateSet(q, drawn, removed)


def judge(feasibility, q, collision=None, workspace=None,
          workers: int | None = None) -> tuple[np.ndarray, dict]:
    """Poses of ``q`` (M, N) meeting every constraint; name → mask of the poses violating it.

    ``feasibility.feasible(q)``, then with a collision model :func:`screen_collisions` of the
    feasible poses, evaluated share by share in forked processes
    (:func:`~doe_calib.runtime.forked.forked_map`, ``workers`` of them, default one per CPU):
    each process judges a run of the draws from the constraints to the tracker's beams. Each
    pose's answer is its own, so the result does not depend on the shares.
    """
    fewest = _DRAWN_SHARE_FREE if collision is None else _DRAWN_SHARE
    shares = max(1, min(_SHARES, len(q) // fewest))
    bounds = np.linspace(0, len(q), shares + 1).astype(int)
    found = forked_map(_judge, (feasibility, collision, q, bounds, workspace), shares, workers)
    ok = np.concatenate([f[0] for f in found])
    violated = {name: np.concatenate([f[1][name] for f in found]) for name in found[0][1]}
    if collision is None:
        return ok, violated
    hit, bodies = np.full(len(q), -1), np.full(len(q), None, dtype=object)
    hit[ok] = np.concatenate([f[2] for f in found])
    bodies[ok] = [b for f in found for b in f[3]]
    ok, masks = _collision_masks(collision, ok, hit, bodies)
    violated.update(masks)
    return ok, violated


def _judge(shared, i: int) -> tuple:
    """Share i of the draws: (feasible mask, name → mask of violators), then with a collision
    model each feasible pose's first pair too close and first body on a blocked beam
    (:func:`_screened`)."""
    feasibility, collision, q, bounds, workspace = shared
    poses = q[bounds[i]:bounds[i + 1]]
    ok, violated = feasibility.feasible(poses)
    if collision is None:
        return ok, violated
    return ok, violated, *_screened(collision, poses[ok], workspace)


def screen_collisions(collision, q, ok, workspace) -> tuple[np.ndarray, dict]:
    """Poses of ``q`` still ok once too-close pairs are rejected; pair → mask of rejected.

    The poses are screened in shares of at least :data:`_SHARE` by forked processes
    (:func:`~doe_calib.runtime.forked.forked_map`, one per CPU); each pose's answer is its
    own, so the result does not depend on the shares.
    """
    shares = np.array_split(np.flatnonzero(ok), max(1, min(_SHARES, ok.sum() // _SHARE)))
    found = forked_map(_screen, (collision, q, shares, workspace), len(shares))
    hit, bodies = np.full(len(q), -1), np.full(len(q), None, dtype=object)
    for share, (hits, blocked) in zip(shares, found):
        hit[share], bodies[share] = hits, blocked
    return _collision_masks(collision, ok, hit, bodies)


def _collision_masks(collision, ok, hit, bodies) -> tuple[np.ndarray, dict]:
    """``ok`` without the poses hit or blocked; a mask per pair hit, then per blocking body."""
    masks = {f"collision: {collision.pair_name(k)}": hit == k for k in np.unique(hit[hit >= 0])}
    ok = ok & (hit < 0)
    for body in sorted({b for b in bodies if b is not None}):
        masks[f"line of sight: blocked by {body}"] = bodies == body
    return ok & np.array([b is None for b in bodies], bool), masks


def _screen(shared, i: int) -> tuple:
    collision, q, shares, workspace = shared
    return _screened(collision, q[shares[i]], workspace)


def _screened(collision, poses, workspace) -> tuple:
    """The first pair too close (−1: none) at each pose, and the first body on a blocked beam
    of each pose found free (None: every beam free, or not checked)."""
    hit = too_close(collision, poses, workspace=workspace)
    bodies = [None] * len(poses)
    if collision.tracker is not None:
        free = np.flatnonzero(hit < 0)
        for k, b in zip(free, screen_beams(collision, poses[free], workspace)):
            bodies[k] = None if b is None else b.body
    return hit, bodies
