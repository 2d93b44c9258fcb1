"""Contact candidates: the tool's ball seated in sockets at their nominal positions.

``doe-calib design --sockets FILE`` designs socket contacts (formats.md §3, *Socket
contacts*; the sockets file, formats.md §4, *Contact designs*). For each socket, tool
orientations are drawn: the stem (flange origin → ball centre) along an approach direction
within a cone of half-angle ``cone`` around the downward vertical (uniform over that cap),
turned about it by a uniform wrist angle; each is seated by inverse kinematics on the
nominal model (:mod:`.seating`) from a random seed (so on varied branches of the arm).
A candidate is kept when it is seated inside the joint bounds, meets every constraint
(:mod:`.feasibility`) and, with a collision model, its clearances; and when its approach
point, the ball ``lift`` back along the approach direction with the same orientation, is
seated on the same branch of the arm (no joint moving more than :data:`NEAR`), feasible
and clear too (the program comes down from there).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np

from doe_calib.collision import Workspace
from doe_calib.design.candidates.draw import CandidateSet, screen_collisions
from doe_calib.design.candidates.reachability import nearest_equivalent
from doe_calib.design.candidates.seating import seat, seating_residual
from doe_calib.errors import OptionError, SolverError
from doe_calib.io.named_rows import read_named_rows

#: Orientations drawn per socket, the approach cone's half-angle (rad) and the lift (m).
PER_SOCKET = 400
CONE = np.radians(40.0)
LIFT = 0.05
#: Largest joint move (rad, m) from a contact to its approach point: beyond it the solve
#: found another branch of the arm, which the straight move up would not keep.
NEAR = 0.5


@dataclass(frozen=True)
class Sockets:
    """Named socket points, nominal, robot base frame: ``names`` (S,), ``points`` (S, 3) m."""

    names: tuple
    points: np.ndarray
    source: str = ""

    def to_dict(self) -> dict:
        """Socket name → point, mm."""
        return {n: [float(v) for v in 1000.0 * p] for n, p in zip(self.names, self.points)}


def read_sockets(path) -> Sockets:
    """The sockets of a CSV ``socket,x,y,z`` (mm, robot base frame), one row each.

    Raises
    ------
    DataError
        A missing column, a value that is not a finite number, a socket named twice, or
        no socket; with the file, line and column.
    """
    path = Path(path)
    names, v, _ = read_named_rows(path, "socket", ("x", "y", "z"), form="the sockets file is a CSV "
                                  "socket,x,y,z (mm, robot base frame)")
    return Sockets(names, np.c_[v["x"], v["y"], v["z"]] / 1000.0, path.name)


@dataclass(frozen=True, eq=False)
class ContactSet(CandidateSet):
    """Contact candidates (a :class:`.draw.CandidateSet` whose ``q`` are seated contacts)
    with each one's ``socket`` (K,) (index into ``sockets.names``: the sockets, or the
    planes or ballbar pivots), its ``approach`` (K, N) joint values (rad, m) at the
    approach point and the ``sockets``. A reading that is one scalar (a touch, a length)
    has its ``direction`` (K, 3), the unit vector its ball rows are read along, and
    ``own`` (K, 3), its row of the eliminated plane's or pivot's own columns (None for
    socket contacts: three rows each, their socket's point eliminated); a ballbar
    position its ``length`` (K,), m."""

    socket: np.ndarray = None
    approach: np.ndarray = None
    sockets: Sockets = None
    direction: np.ndarray = None
    own: np.ndarray = None
    length: np.ndarray = None


@dataclass(frozen=True)
class SocketContacts:
    """What contact candidates to draw: ``sockets``, the tool's ``ball`` marker (its index),
    orientations ``per_socket``, the approach ``cone`` (rad) and the ``lift`` (m)."""

    sockets: Sockets
    ball: int = 0
    per_socket: int = PER_SOCKET
    cone: float = CONE
    lift: float = LIFT
    #: What the readings are: "socket" contacts, "plane" touches, "ballbar" positions.
    kind: ClassVar[str] = "socket"

    @classmethod
    def of_tool(cls, sockets: Sockets, tool, ball: str | None = None, **settings):
        """For ``tool``: its marker ``ball``, or its only marker.

        Raises
        ------
        OptionError
            No such marker, or several markers and none named.
        """
        if ball is None:
            if tool.n_markers != 1:
                raise OptionError(f"socket contacts seat one ball: the tool has "
                                  f"{tool.n_markers} markers ({', '.join(tool.names)}); name "
                                  f"the ball (--ball)")
            return cls(sockets, 0, **settings)
        if ball not in tool.names:
            raise OptionError(f"--ball {ball!r}: no such marker in the tool; markers: "
                              f"{', '.join(tool.names)}")
        return cls(sockets, tool.index(ball), **settings)

    def draw(self, feasibility, model, values, rng, collision=None) -> ContactSet:
        """The contact candidates (module notes); ``values`` the parameters placing the
        robot (SI). Raises SolverError when a socket keeps none."""
        s = len(self.sockets.names)
        ball = model.tool.position_array[self.ball]
        k = s * self.per_socket
        socket = np.repeat(np.arange(s), self.per_socket)
        down, rotation = orientations(ball, k, self.cone, rng)
        target = self.sockets.points[socket]
        return seated_candidates(feasibility, model, values, rng, collision, self.ball,
                                 target, rotation, -self.lift * down, socket,
                                 self.sockets.names, "socket", self.sockets.source,
                                 sockets=self.sockets)


def orientations(ball, k: int, cone: float, rng, axes=None) -> tuple:
    """Stem directions (K, 3), base frame, within ``cone`` (rad) of the downward vertical,
    or of each of ``axes`` (K, 3) (unit), uniform over that cap; and flange rotations
    (K, 3, 3) that point the stem (flange origin → ``ball``, flange frame) along them,
    turned about them by a random wrist angle."""
    stem = ball / np.linalg.norm(ball) if np.linalg.norm(ball) > 1e-6 else np.r_[0, 0, 1.0]
    tilt = np.arccos(1.0 - rng.uniform(0.0, 1.0, k) * (1.0 - np.cos(cone)))
    azimuth, wrist = rng.uniform(0.0, 2 * np.pi, (2, k))
    down = np.c_[np.sin(tilt) * np.cos(azimuth), np.sin(tilt) * np.sin(azimuth),
                 -np.cos(tilt)]
    if axes is not None:
        down = np.einsum("kij,kj->ki", _aligning(np.r_[0, 0, -1.0], axes), down)
    onto = _aligning(stem, down)
    return down, np.einsum("kij,kjl->kil", _about(down, wrist), onto)


def seated_candidates(feasibility, model, values, rng, collision, ball: int, targets,
                      rotations, away, group, names, kind: str, source: str,
                      **fields) -> ContactSet:
    """The candidates that seat the tool's marker ``ball`` on ``targets`` (K, 3), m, with
    the flange at ``rotations`` (K, 3, 3), from random seeds: those seated inside the joint
    bounds, feasible and clear, whose approach point (the ball moved by ``away`` (K, 3), m;
    all zero: none) is seated on the same branch of the arm, feasible and clear too.

    ``group`` (K,) indexes ``names``, the sockets, planes or pivots (``kind`` in words);
    ``fields``: the :class:`ContactSet`'s own, those of one row per candidate (K, …) kept
    for the candidates kept. Raises SolverError when a group keeps none.
    """
    robot = model.robot
    lo, hi = feasibility.constraints.bounds(robot)
    revolute = np.array([j.kind == "revolute" for j in robot.joints])
    residual = seating_residual(model, values, model.tool.position_array[ball])
    k = len(targets)
    q, ok = seat(residual, targets, rotations, rng.uniform(lo, hi, (k, len(lo))), lo, hi,
                 revolute)
    removed = {"not seated inside the joint limits": int((~ok).sum())}
    ok &= _screen(feasibility, collision, q, ok, removed, "")
    if np.any(away):
        up, ok_up = seat(residual, targets + away, rotations, q, lo, hi, revolute)
        up = nearest_equivalent(up, q, robot, lo, hi)
        lifted = ok & ~ok_up
        removed["approach point not seated inside the joint limits"] = int(lifted.sum())
        ok &= ok_up
        far = ok & (np.abs(up - q).max(axis=1) > NEAR)
        removed["approach point on another branch of the arm"] = int(far.sum())
        ok &= ~far & _screen(feasibility, collision, up, ok & ~far, removed,
                             "approach point: ")
    else:
        up = q.copy()
    per = np.bincount(group, minlength=len(names))
    for j, name in enumerate(names):
        if not ok[group == j].any():
            raise SolverError(f"{kind} {name}: none of {per[j]} tool orientations is seated "
                              f"within the joint limits and the constraints; is it within "
                              f"reach?")
    removed = {why: n for why, n in removed.items() if n}
    kept = group[ok]
    labels = tuple(f"{names[j]}-{int(np.sum(kept[:i] == j)) + 1}" for i, j in enumerate(kept))
    return ContactSet(q[ok], k, removed, labels, source, group[ok], up[ok],
                      **{f: (v[ok] if isinstance(v, np.ndarray) and len(v) == k else v)
                         for f, v in fields.items()})


def _screen(feasibility, collision, q, ok, removed: dict, prefix: str) -> np.ndarray:
    """Those of ``q`` (where ``ok``) that meet the constraints and clearances; the
    violations counted into ``removed`` under ``prefix``."""
    good, violated = feasibility.feasible(q)
    good &= ok
    if collision is not None and good.any():
        good, hits = screen_collisions(collision, q, good, Workspace(collision))
        violated.update(hits)
    for name, v in violated.items():
        removed[prefix + name] = removed.get(prefix + name, 0) + int((v & ok).sum())
    return good


def _aligning(a, b) -> np.ndarray:
    """Rotations (K, 3, 3) taking the unit vector ``a`` (3,) onto each unit row of ``b``
    (K, 3), the shortest turn (half a turn about an axis normal to ``a`` when opposite)."""
    v, c = np.cross(a, b), b @ a
    vx = np.zeros((len(b), 3, 3))
    vx[:, 0, 1], vx[:, 0, 2], vx[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    vx -= vx.transpose(0, 2, 1)
    out = np.eye(3) + vx + vx @ vx / np.maximum(1.0 + c, 1e-12)[:, None, None]
    normal = np.cross(a, [1.0, 0, 0] if abs(a[0]) < 0.9 else [0, 1.0, 0])
    normal /= np.linalg.norm(normal)
    flip = 2 * np.outer(normal, normal) - np.eye(3)
    return np.where((c < -1 + 1e-9)[:, None, None], flip, out)


def _about(axes, angles) -> np.ndarray:
    """Rotations (K, 3, 3) by ``angles`` (K,) about the unit ``axes`` (K, 3) (Rodrigues)."""
    kx = np.zeros((len(axes), 3, 3))
    kx[:, 0, 1], kx[:, 0, 2], kx[:, 1, 2] = -axes[:, 2], axes[:, 1], -axes[:, 0]
    kx -= kx.transpose(0, 2, 1)
    s, c = np.sin(angles)[:, None, None], np.cos(angles)[:, None, None]
    return np.eye(3) + s * kx + (1 - c) * kx @ kx
