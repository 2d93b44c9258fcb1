"""Candidate poses from a file: taught, known-safe or already-measured configurations.

``doe-calib design --candidates-from FILE`` designs over the poses of a
design CSV or JSON (formats.md §4) or a measurement CSV (formats.md §3)
instead of random ones. Each distinct pose id is one candidate (its first
row's joint positions); the file's wrenches are not used, since a designed
pose is measured unloaded and under every ``--load``. The candidates still
pass every constraint and the collision screening, and the rejections are
counted as for random candidates; the chosen poses keep their ids.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from doe_calib.collision import Workspace
from doe_calib.design.candidates.draw import CandidateSet, screen_collisions
from doe_calib.design.result import first_rows
from doe_calib.errors import DataError, SolverError
from doe_calib.io.csv_files import read_design, read_measurements
from doe_calib.io.table import read_table


@dataclass(frozen=True, eq=False)
class CandidatePoses:
    """Named poses to design over.

    Attributes
    ----------
    q : ndarray, shape (K, N)
        Joint positions, rad (m for prismatic joints).
    names : tuple of str, length K
        Pose id of each (distinct).
    source : str
        Where they come from (a file name).
    """

    q: np.ndarray
    names: tuple
    source: str = ""

    def __len__(self) -> int:
        return len(self.names)

    @classmethod
    def from_configurations(cls, configurations, source: str = "") -> "CandidatePoses":
        """One candidate per distinct pose id of ``configurations`` (its first row's q)."""
        index = first_rows(configurations)
        return cls(configurations.q[index], tuple(configurations.pose[i] for i in index), source)


def _is_measurement_csv(path) -> bool:
    columns = {c.strip().lower() for c in read_table(path).columns}
    return {"x", "y", "z"} <= columns or "marker" in columns


def read_candidates(path, robot, tool=None) -> CandidatePoses:
    """The candidate poses of a design CSV/JSON or a measurement CSV.

    Parameters
    ----------
    path : path-like
        A ``.json`` design, a design CSV (``pose, q1..qN`` …) or a measurement
        CSV (``pose, marker, x, y, z, q1..qN`` …; recognised by its x, y, z or
        marker columns).
    robot : Robot
    tool : Tool, optional
        Needed for a measurement CSV (its marker names).

    Raises
    ------
    DataError
        A measurement CSV without ``tool``, or a file without any pose.
    """
    path = Path(path)
    if path.suffix.lower() != ".json" and _is_measurement_csv(path):
        if tool is None:
            raise DataError("a measurement CSV as candidates needs the tool (its markers)", path)
        cfg = read_measurements(path, robot, tool, require_xyz=False).configurations
    else:
        cfg = read_design(path, robot)
    if len(cfg) == 0:
        raise DataError("no pose to use as a candidate", path)
    return CandidatePoses.from_configurations(cfg, path.name)


def screened_candidates(feasibility, robot, candidates: CandidatePoses,
                        collision=None) -> CandidateSet:
    """The poses of ``candidates`` that meet every constraint of ``feasibility``
    (:func:`.feasibility.build_feasibility`) and, with a collision model, their clearance.

    Returns a CandidateSet: ``drawn`` the file's poses, ``removed`` the constraints' counts,
    ``names`` and ``source`` from the file. Raises SolverError when none is feasible.
    """
    q = np.asarray(candidates.q, float)
    ok, violated = feasibility.feasible(q)
    lo, hi = feasibility.constraints.bounds(robot)
    outside = ((q < lo) | (q > hi)).any(axis=1)
    violated["joint limits (with margin)"] = outside
    ok = ok & ~outside
    if collision is not None:
        ok, hits = screen_collisions(collision, q, ok, Workspace(collision))
        violated.update(hits)
    removed = {name: int(v.sum()) for name, v in violated.items() if v.sum()}
    if not ok.any():
        worst = max(removed, key=removed.get) if removed else "the constraints"
        raise SolverError(f"none of the {len(q)} poses of {candidates.source or 'the file'} "
                          f"satisfies the constraints; {worst} removed {removed.get(worst, 0)}, "
                          f"the most of any")
    names = tuple(n for n, k in zip(candidates.names, ok) if k)
    return CandidateSet(q[ok], len(q), removed, names, candidates.source)
