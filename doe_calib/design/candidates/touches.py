"""Plane-touch candidates: the tool's ball brought onto faces at their nominal positions.

``doe-calib design --planes FILE`` designs plane touches (formats.md §3, *Plane touches*;
the planes file, formats.md §4, *Contact designs*). Each face is a plane of the ball's
centre, given by a point, its normal (towards the robot: the side the ball comes from) and
the half-size of the square patch about the point that may be touched. For each face,
points of the patch are drawn uniformly, each with a tool orientation whose stem (flange
origin → ball centre) lies within a cone of half-angle ``cone`` around the inward normal
(uniform over that cap), turned about it by a uniform wrist angle; each is seated by
inverse kinematics on the nominal model (:mod:`.seating`) from a random seed. A candidate
is kept as a socket contact is (:func:`.sockets.seated_candidates`): its approach point is
the ball ``lift`` off the face along the normal, with the same orientation.

A touch is one scalar, the ball's distance along the normal; the plane it lies on is
eliminated (3 numbers: its offset and two tilts), whose own columns at a touch are
``[1, e₁·(x − c), e₂·(x − c)]`` (c the face's point, e₁, e₂ its in-plane axes):
:mod:`~doe_calib.estimation.planes`, at the nominal plane.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np

from doe_calib.design.candidates.sockets import (SocketContacts, orientations,
                                                 seated_candidates)
from doe_calib.errors import DataError
from doe_calib.io.named_rows import read_named_rows

#: The planes file's columns: id, a point of the face, its normal, the patch's half-size.
COLUMNS = ("plane", "x", "y", "z", "nx", "ny", "nz", "half")


@dataclass(frozen=True)
class Planes:
    """Named faces, nominal, robot base frame: ``names`` (S,), a ``points`` (S, 3) m of each,
    its unit ``normals`` (S, 3) and the ``half`` (S,) m size of its square patch."""

    names: tuple
    points: np.ndarray
    normals: np.ndarray
    half: np.ndarray
    source: str = ""

    def axes(self) -> np.ndarray:
        """In-plane unit axes e₁, e₂ of each face (S, 2, 3)."""
        out = []
        for n in self.normals:
            e1 = np.cross(n, [0.0, 0.0, 1.0] if abs(n[2]) < 0.9 else [1.0, 0.0, 0.0])
            e1 /= np.linalg.norm(e1)
            out.append([e1, np.cross(n, e1)])
        return np.array(out)

    def to_dict(self) -> dict:
        """Plane name → its ``point`` (mm), ``normal`` and ``half_mm``."""
        return {n: {"point": [float(v) for v in 1000.0 * p], "normal": [float(v) for v in u],
                    "half_mm": float(1000.0 * h)}
                for n, p, u, h in zip(self.names, self.points, self.normals, self.half)}

    @classmethod
    def from_dict(cls, d: dict) -> "Planes":
        return cls(tuple(d), np.array([v["point"] for v in d.values()], float) / 1000.0,
                   np.array([v["normal"] for v in d.values()], float),
                   np.array([v["half_mm"] for v in d.values()], float) / 1000.0)


def read_planes(path) -> Planes:
    """The faces of a CSV ``plane,x,y,z,nx,ny,nz,half`` (mm, robot base frame; the normal
    need not be unit), one row each.

    Raises
    ------
    DataError
        A missing column, a value that is not a finite number, a zero normal, a half-size
        not positive, a plane named twice, or no plane; with the file, line and column.
    """
    path = Path(path)
    names, v, lines = read_named_rows(path, "plane", COLUMNS[1:], form="the planes file is a "
                                      "CSV plane,x,y,z,nx,ny,nz,half (mm, robot base frame)")
    normal = np.c_[v["nx"], v["ny"], v["nz"]]
    for k, line in enumerate(lines):
        if np.linalg.norm(normal[k]) == 0:
            raise DataError("a zero normal: give the face's normal, towards the robot", path,
                            line, "nx")
        if v["half"][k] <= 0:
            raise DataError(f"half-size {v['half'][k]:g} mm: the patch's half-size is "
                            f"positive", path, line, "half")
    return Planes(names, np.c_[v["x"], v["y"], v["z"]] / 1000.0,
                  normal / np.linalg.norm(normal, axis=1, keepdims=True), v["half"] / 1000.0,
                  path.name)


@dataclass(frozen=True)
class PlaneTouches(SocketContacts):
    """What touch candidates to draw: the faces (``sockets``: :class:`Planes`), the tool's
    ``ball``, tool orientations ``per_socket`` per face, the ``cone`` (rad) around the
    normal and the ``lift`` (m) of the approach point off the face."""

    kind: ClassVar[str] = "plane"

    def draw(self, feasibility, model, values, rng, collision=None):
        """The touch candidates (module notes); ``values`` the parameters placing the robot
        (SI). Raises SolverError when a face keeps none."""
        planes = self.sockets
        s = len(planes.names)
        k = s * self.per_socket
        group = np.repeat(np.arange(s), self.per_socket)
        normal, axes = planes.normals[group], planes.axes()[group]
        _, rotation = orientations(model.tool.position_array[self.ball], k, self.cone, rng,
                                   -normal)
        at = rng.uniform(-1.0, 1.0, (k, 2)) * planes.half[group, None]
        target = planes.points[group] + np.einsum("ka,kai->ki", at, axes)
        return seated_candidates(feasibility, model, values, rng, collision, self.ball,
                                 target, rotation, self.lift * normal, group, planes.names,
                                 "plane", planes.source, sockets=planes, direction=normal,
                                 own=np.c_[np.ones(k), at])
