"""Readings in metres where millimetres are due, told from the robot's own geometry.

The RMS distance of points from their centroid does not change under a rigid
motion, so the readings' spread in the tracker frame equals the spread of the
same points in the robot's base frame. The nominal model (the URDF's chain at
the file's joint values, the tool file's marker positions) puts every reading
somewhere; the two spreads agree within the calibration errors (millimetres
on a spread of decimetres to metres). Coordinates written in metres and read
as millimetres spread 1000 times less: a ratio no calibration error can
make. Each session is centred on its own (a session may have its own tracker
placement).
"""
from __future__ import annotations

import numpy as np

#: Readings spread / nominal spread inside this range: the readings are in metres (1/1000).
METRES_RATIO = (1e-4, 1e-2)
#: Below this nominal spread (m) the configurations hardly move the markers: no verdict.
MIN_NOMINAL_SPREAD_M = 0.05
#: Configurations used for the nominal positions at most (evenly drawn), for speed.
MAX_CONFIGURATIONS = 2000


def nominal_points(robot, q, config, offsets) -> np.ndarray:
    """Where the nominal robot puts each reading, robot base frame, m.

    Parameters
    ----------
    robot : Robot
    q : ndarray, shape (M, N)
        Joint values of the configurations, rad (m for prismatic joints).
    config : ndarray of int, shape (K,)
        Configuration of each reading.
    offsets : ndarray, shape (K, 3)
        Position of each reading's point in the flange frame, m (a marker's
        position; zeros for a probe frame's origin).

    Returns
    -------
    ndarray, shape (K, 3)
    """
    rot, trans = robot.flange_poses(q)
    return np.einsum("kij,kj->ki", rot[config], offsets) + trans[config]


def spread(points, groups) -> float:
    """RMS distance of ``points`` (K, 3) from the centroid of their group (K,); NaN rows skipped."""
    points = np.asarray(points, float)
    keep = np.isfinite(points).all(axis=1)
    points, groups = points[keep], np.asarray(groups)[keep]
    if not len(points):
        return float("nan")
    _, of = np.unique(groups, return_inverse=True)
    centres = np.array([np.bincount(of, points[:, a]) for a in range(3)]).T / \
        np.bincount(of)[:, None]
    return float(np.sqrt(np.mean(np.sum((points - centres[of]) ** 2, axis=1))))


def metres_finding(xyz, robot, q, config, offsets, sessions) -> str | None:
    """Words naming x, y, z as metres when their spread is ~1/1000 of the nominal one, else None.

    Parameters
    ----------
    xyz : ndarray, shape (K, 3)
        The readings as read, i.e. the file's numbers / 1000 (m if the file was in mm).
    robot : Robot
    q, config, offsets :
        As :func:`nominal_points`.
    sessions : ndarray, shape (K,)
        Session of each reading (each is centred on its own).

    Examples
    --------
    >>> from doe_calib import Robot, examples
    >>> robot = Robot.from_urdf(examples.THREE_DOF_URDF)
    >>> q = np.array([[0.0, 0.5, -0.5], [1.0, -0.5, 0.8], [2.0, 0.3, 0.1]])
    >>> p = nominal_points(robot, q, np.arange(3), np.zeros((3, 3)))
    >>> metres_finding(p, robot, q, np.arange(3), np.zeros((3, 3)), np.zeros(3)) is None
    True
    >>> "look like metres" in metres_finding(p / 1000, robot, q, np.arange(3), np.zeros((3, 3)),
    ...                                      np.zeros(3))
    True
    """
    xyz, config = np.asarray(xyz, float), np.asarray(config)
    if not np.isfinite(xyz).any():
        return None
    used = np.unique(config)  # sorted
    if len(used) > MAX_CONFIGURATIONS:
        used = used[np.linspace(0, len(used) - 1, MAX_CONFIGURATIONS).astype(int)]
    rows = np.flatnonzero(np.isin(config, used))
    nominal = nominal_points(robot, np.asarray(q)[used], np.searchsorted(used, config[rows]),
                             np.asarray(offsets, float)[rows])
    groups = np.asarray(sessions)[rows]
    expected, found = spread(nominal, groups), spread(xyz[rows], groups)
    if not expected >= MIN_NOMINAL_SPREAD_M:
        return None
    ratio = found / expected
    if not METRES_RATIO[0] <= ratio <= METRES_RATIO[1]:
        return None
    return (f"x, y, z look like metres, not mm: the readings spread {found * 1e3:.3g} about "
            f"their centre (RMS, file units) where the robot's nominal model puts these points "
            f"{expected * 1e3:.0f} mm from theirs ({1 / ratio:.0f}× more; the robot reaches "
            f"about {robot.link_lengths.sum():.2f} m); multiply x, y, z by 1000")
