"""Ballbar candidates: the tool's ball at a ballbar's lengths from its pivot.

``doe-calib design --ballbar PIVOT`` designs ballbar positions (formats.md §3, *Ballbar
and gauge lengths*; the option, formats.md §4, *Contact designs*). For each pivot (the
bar's table end, nominal) and each of its lengths, directions are drawn uniformly over the
upper half sphere above :data:`MIN_ELEVATION`; the ball's centre is put at that length
along it, the stem (flange origin → ball centre) within a cone of half-angle ``cone``
around the bar, towards the pivot (the cup holding the ball is in line with the bar),
turned about it by a uniform wrist angle; each is seated by inverse kinematics on the
nominal model (:mod:`.seating`) from a random seed, and kept when it is inside the joint
bounds, feasible and clear. A magnetic ballbar stays mounted: there is no approach point.

A position is one scalar, the length; the pivot is eliminated (3 numbers), whose own
columns at a position are uᵀ, u the bar's unit direction (:mod:`~doe_calib.estimation.
ballbar`, at the nominal pivot).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from doe_calib.design.candidates.sockets import (SocketContacts, orientations,
                                                 seated_candidates)
from doe_calib.errors import OptionError

#: Lowest elevation of the bar above the pivot's horizontal plane (rad): the bar clears the
#: table the pivot stands on.
MIN_ELEVATION = np.radians(10.0)


@dataclass(frozen=True)
class Pivots:
    """Named ballbar pivots, nominal, robot base frame: ``names`` (S,), ``points`` (S, 3) m
    and each one's ``lengths`` (tuples, m)."""

    names: tuple
    points: np.ndarray
    lengths: tuple
    source: str = ""

    def to_dict(self) -> dict:
        """Pivot name → its ``point`` and ``lengths_mm``."""
        return {n: {"point": [float(v) for v in 1000.0 * p],
                    "lengths_mm": [float(1000.0 * x) for x in ls]}
                for n, p, ls in zip(self.names, self.points, self.lengths)}

    @classmethod
    def from_dict(cls, d: dict) -> "Pivots":
        return cls(tuple(d), np.array([v["point"] for v in d.values()], float) / 1000.0,
                   tuple(tuple(x / 1000.0 for x in v["lengths_mm"]) for v in d.values()))


def parse_pivots(specs) -> Pivots:
    """The pivots of ``--ballbar`` options, each ``X,Y,Z:LENGTH[,LENGTH...]`` (mm, robot
    base frame), named P1, P2, … in order.

    Raises
    ------
    OptionError
        A spec not of that form, a length not positive.
    """
    points, lengths = [], []
    for spec in specs:
        where, _, bars = spec.partition(":")
        try:
            xyz = [float(v) for v in where.split(",")]
            bar = [float(v) for v in bars.split(",")] if bars else []
        except ValueError:
            xyz, bar = [], []
        if len(xyz) != 3 or not bar or not np.all(np.isfinite(xyz + bar)):
            raise OptionError(f"--ballbar {spec}: give the pivot and its lengths as "
                              f"X,Y,Z:LENGTH[,LENGTH...] (mm, robot base frame)")
        if min(bar) <= 0:
            raise OptionError(f"--ballbar {spec}: a ballbar's length is positive (mm)")
        points.append(xyz)
        lengths.append(tuple(x / 1000.0 for x in bar))
    return Pivots(tuple(f"P{k + 1}" for k in range(len(points))),
                  np.array(points, float) / 1000.0, tuple(lengths), "--ballbar")


@dataclass(frozen=True)
class BallbarPositions(SocketContacts):
    """What ballbar candidates to draw: the ``sockets`` (:class:`Pivots`), the tool's
    ``ball``, positions ``per_socket`` per pivot (over its lengths in turn) and the stem's
    ``cone`` (rad) around the bar; no ``lift``."""

    kind: ClassVar[str] = "ballbar"
    lift: float = 0.0

    def draw(self, feasibility, model, values, rng, collision=None):
        """The ballbar candidates (module notes); ``values`` the parameters placing the
        robot (SI). Raises SolverError when a pivot keeps none."""
        pivots = self.sockets
        s = len(pivots.names)
        k = s * self.per_socket
        group = np.repeat(np.arange(s), self.per_socket)
        length = np.array([pivots.lengths[g][i % len(pivots.lengths[g])]
                           for i, g in enumerate(group)])
        up = rng.uniform(np.sin(MIN_ELEVATION), 1.0, k)
        azimuth = rng.uniform(0.0, 2 * np.pi, k)
        flat = np.sqrt(1.0 - up ** 2)
        bar = np.c_[flat * np.cos(azimuth), flat * np.sin(azimuth), up]
        _, rotation = orientations(model.tool.position_array[self.ball], k, self.cone, rng,
                                   -bar)
        target = pivots.points[group] + length[:, None] * bar
        return seated_candidates(feasibility, model, values, rng, collision, self.ball,
                                 target, rotation, np.zeros((k, 3)), group, pivots.names,
                                 "pivot", pivots.source, sockets=pivots, direction=bar,
                                 own=bar, length=length)
