"""Candidate poses: random joint angles inside the bounds that satisfy every constraint."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doe_calib.collision import Workspace, screen_beams, too_close
from doe_calib.design.result import CandidateCount
from doe_calib.errors import SolverError

_MAX_DRAWS = 50  # draw at most this many poses per candidate wanted


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


def feasible_candidates(feasibility, robot, n: int, rng, collision=None) -> CandidateSet:
    """``n`` poses drawn uniformly inside the bounds and kept if feasible.

    Draws in rounds sized by the acceptance rate so far, up to
    ``50 n`` poses in all. With a :class:`~doe_calib.collision.CollisionModel`,
    the poses meeting every other constraint are also screened for pairs
    closer than their clearance; each rejected pose is counted under the
    first such pair (``"collision: upper_arm_link vs floor"``). When the
    collision model has a tracker, the poses left whose beam to a marker is
    blocked are counted under the body blocking it
    (``"line of sight: blocked by forearm_link"``).

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
        ok, violated = feasibility.feasible(q)
        if collision is not None:
            ok, hits = screen_collisions(collision, q, ok, workspace)
            violated.update(hits)
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


def screen_collisions(collision, q, ok, workspace) -> tuple[np.ndarray, dict]:
    """Poses of ``q`` still ok once too-close pairs are rejected; pair → mask of rejected."""
    hit = np.full(len(q), -1)
    hit[ok] = too_close(collision, q[ok], workspace=workspace)
    masks = {f"collision: {collision.pair_name(k)}": hit == k for k in np.unique(hit[hit >= 0])}
    ok = ok & (hit < 0)
    if collision.tracker is not None:
        bodies = np.full(len(q), None, dtype=object)
        bodies[ok] = [None if b is None else b.body
                      for b in screen_beams(collision, q[ok], workspace)]
        for body in sorted({b for b in bodies if b is not None}):
            masks[f"line of sight: blocked by {body}"] = bodies == body
        ok = ok & np.array([b is None for b in bodies])
    return ok, masks
