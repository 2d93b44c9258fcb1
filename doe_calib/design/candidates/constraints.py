"""What a measurement pose must satisfy: the design constraints, parsed and validated once.

Everything is SI here (rad/m, N·m/N); :meth:`DesignConstraints.to_dict`
gives the file's units (deg/mm). Points and boxes are in the robot base
frame; the flange, every marker and every load's centre of mass (with
``load_clearance`` around it) must respect the Cartesian constraints. Read
a file with :func:`doe_calib.design.candidates.constraint_file.read_constraints`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Margin kept inside every joint limit when none is given: deg (mm for prismatic joints).
DEFAULT_MARGIN = 1.0


@dataclass(frozen=True)
class Box:
    """An axis-aligned box in the robot base frame: corners in m."""

    name: str
    lower: tuple
    upper: tuple

    def to_dict(self) -> dict:
        return {"name": self.name, "min": [1000.0 * v for v in self.lower],
                "max": [1000.0 * v for v in self.upper]}


@dataclass(frozen=True)
class LineOfSight:
    """Each marker faces the tracker within ``max_incidence``.

    Attributes
    ----------
    tracker : tuple of 3 float
        Tracker position in the robot base frame, m.
    max_incidence : float
        Largest angle between a marker's normal and its line to the tracker, rad.
    normals : tuple of tuple of 3 float
        Unit normal of each marker (tool order) in the flange frame.
    """

    tracker: tuple
    max_incidence: float
    normals: tuple


@dataclass(frozen=True)
class Coverage:
    """At least ``min_bins`` of the bins ``edges`` (SI, increasing) of one joint are used."""

    joint: int
    edges: tuple
    min_bins: int

    def bins(self, q: np.ndarray) -> np.ndarray:
        """Bin (0-based) of each pose of q (M, N); −1 outside every bin."""
        x = np.atleast_2d(q)[:, self.joint]
        b = np.searchsorted(self.edges, x, side="right") - 1
        b[x == self.edges[-1]] = len(self.edges) - 2
        return np.where((b >= 0) & (b < len(self.edges) - 1), b, -1)

    def used(self, q: np.ndarray) -> list[int]:
        """The distinct bins the poses q use, sorted."""
        return sorted(set(self.bins(q).tolist()) - {-1})


@dataclass(frozen=True)
class DesignConstraints:
    """Every constraint on the measurement poses.

    Attributes
    ----------
    lower, upper : tuple of float
        Joint limits (URDF, narrowed by the file), rad or m; ±inf when unbounded.
    margin : float
        Kept clear inside every limit: deg for revolute joints, mm for prismatic.
    keep_out : tuple of Box
    keep_in : Box or None
    floor : float or None
        Lowest allowed z in the robot base frame, m.
    load_clearance : float
        Radius kept free around each load's centre of mass, m.
    line_of_sight : LineOfSight or None
    torque_limits : tuple of float or None
        Largest |τ_k| each joint may bear from a load, N·m (N); inf: no limit.
    coverage : Coverage or None
    source : str
        File the constraints came from ("" for defaults).
    """

    lower: tuple
    upper: tuple
    margin: float = DEFAULT_MARGIN
    keep_out: tuple = ()
    keep_in: Box | None = None
    floor: float | None = None
    load_clearance: float = 0.0
    line_of_sight: LineOfSight | None = None
    torque_limits: tuple | None = None
    coverage: Coverage | None = None
    source: str = ""

    @classmethod
    def from_robot(cls, robot, margin: float = DEFAULT_MARGIN) -> "DesignConstraints":
        """Only the URDF joint limits and a margin (deg, mm for prismatic joints)."""
        return cls(tuple(robot.lower), tuple(robot.upper), margin)

    def bounds(self, robot) -> tuple[np.ndarray, np.ndarray]:
        """Joint bounds the poses live in, margin applied, shape (N,) each, rad/m.

        Unbounded joints are taken in [−π, π].
        """
        lo = np.where(np.isfinite(self.lower), self.lower, -np.pi)
        hi = np.where(np.isfinite(self.upper), self.upper, np.pi)
        m = self.margin / robot.display_factors
        return lo + m, hi - m

    @property
    def cartesian(self) -> bool:
        """Whether any Cartesian constraint is set."""
        return bool(self.keep_out) or self.keep_in is not None or self.floor is not None

    def to_dict(self, robot, tool) -> dict:
        """JSON-able form in the file's units: deg (mm), mm, N·m."""
        f = robot.display_factors
        out = {"source": self.source, "units": "deg (mm for prismatic joints), mm, N·m (N)",
               "joint_limits": {j.name: [_finite(lo * k), _finite(hi * k)] for j, lo, hi, k
                                in zip(robot.joints, self.lower, self.upper, f)},
               "margin": self.margin}
        if self.cartesian or self.load_clearance:
            out["cartesian"] = {"keep_out": [b.to_dict() for b in self.keep_out],
                                "keep_in": self.keep_in.to_dict() if self.keep_in else None,
                                "floor": None if self.floor is None else 1000.0 * self.floor,
                                "load_clearance": 1000.0 * self.load_clearance}
        if self.line_of_sight is not None:
            los = self.line_of_sight
            out["line_of_sight"] = {"tracker": [1000.0 * v for v in los.tracker],
                                    "max_incidence": float(np.degrees(los.max_incidence)),
                                    "normals": {n: list(v) for n, v in
                                                zip(tool.names, los.normals)}}
        if self.torque_limits is not None:
            out["load_torque"] = {j.name: t for j, t in zip(robot.joints, self.torque_limits)
                                  if np.isfinite(t)}
        if self.coverage is not None:
            c = self.coverage
            out["coverage"] = {"joint": robot.joints[c.joint].name,
                               "edges": [e * f[c.joint] for e in c.edges],
                               "min_bins": c.min_bins}
        return out


def _finite(x: float):
    return float(x) if np.isfinite(x) else None
