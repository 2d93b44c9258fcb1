"""A 6-DoF probe file: the probe's position and three angles per pose (formats.md §3b).

A 6-DoF probe (a tracker's T-Mac or 6-DoF SMR, a mocap rigid body) reads
the full pose of a frame on the flange: ``x, y, z`` (mm) and three angles
``a, b, c`` (deg) in the device frame. The angle convention is stated by
the caller (:data:`ANGLE_CONVENTIONS`), the rotation ``R`` maps probe-frame
vectors into the device frame:

* ``rpy``: roll a about x, pitch b about y, yaw c about z, fixed axes:
  ``R = Rz(c)·Ry(b)·Rx(a)`` (URDF, ROS);
* ``xyz-euler``: intrinsic x, y′, z″: ``R = Rx(a)·Ry(b)·Rz(c)``;
* ``zyx-euler``: intrinsic z, y′, x″: ``R = Rz(a)·Ry(b)·Rx(c)`` (KUKA A, B, C);
* ``rotvec``: ``(a, b, c)`` is the rotation vector, deg.

The configuration columns are those of a measurement file (pose, q1..qN,
optional wrench, temperature, session), one row per pose and load.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from doe_calib.errors import DataError
from doe_calib.io.configuration_columns import (
    LIMIT_TOLERANCE,
    WRENCH,
    XYZ,
    check_width,
    codes,
    combined,
    derived_approach,
    joint_columns,
    joints,
    numbers,
    texts,
)
from doe_calib.io.measurements import Configurations
from doe_calib.io.reading_units import metres_finding
from doe_calib.io.row_problems import RowProblems, earlier_in_group
from doe_calib.io.table import read_table

#: Angle convention → scipy's sequence (lower case: fixed axes; upper case: intrinsic).
ANGLE_CONVENTIONS = {"rpy": "xyz", "xyz-euler": "XYZ", "zyx-euler": "ZYX", "rotvec": None}
ANGLES = ("a", "b", "c")


def angles_to_matrix(angles_deg, convention: str) -> np.ndarray:
    """Rotation matrices from three angles per row in ``convention``.

    Parameters
    ----------
    angles_deg : array_like, shape (M, 3)
        Angles in degrees (a rotation vector in degrees for ``rotvec``).
    convention : str
        One of :data:`ANGLE_CONVENTIONS`.

    Returns
    -------
    ndarray, shape (M, 3, 3)

    Examples
    --------
    >>> r = angles_to_matrix([[0, 0, 90]], "rpy")[0]
    >>> np.round(r @ [1, 0, 0], 12).tolist()
    [0.0, 1.0, 0.0]
    """
    if convention not in ANGLE_CONVENTIONS:
        raise ValueError(f"unknown angle convention {convention!r}; choose one of "
                         f"{', '.join(ANGLE_CONVENTIONS)}")
    a = np.radians(np.atleast_2d(np.asarray(angles_deg, float)))
    seq = ANGLE_CONVENTIONS[convention]
    rot = Rotation.from_rotvec(a) if seq is None else Rotation.from_euler(seq, a)
    return rot.as_matrix().reshape(-1, 3, 3)


@dataclass(frozen=True, eq=False)
class ProbeReadings:
    """Probe poses, one per configuration, in SI.

    Attributes
    ----------
    configurations : Configurations
        The M configurations, in file order.
    position : ndarray, shape (M, 3)
        Probe origin in the device frame, m.
    rotation : ndarray, shape (M, 3, 3)
        Probe orientation in the device frame (probe → device).
    line : ndarray of int, shape (M,)
        Source line of each row.
    source : str
        The file, for messages.
    session : tuple of str
        Session of each configuration.
    warnings : tuple of str
        Rows accepted with a doubt (a joint a hair past its limit).
    """

    configurations: Configurations
    position: np.ndarray
    rotation: np.ndarray
    line: np.ndarray
    source: str = ""
    session: tuple = ()
    warnings: tuple = ()

    def __len__(self) -> int:
        return len(self.configurations)


def read_probe(path, robot, convention: str) -> ProbeReadings:
    """Read a 6-DoF probe file (formats.md §3b).

    Parameters
    ----------
    path : path-like
    robot : Robot
        Gives N (columns q1..qN, deg or mm) and the joint limits.
    convention : str
        Angle convention of ``a, b, c`` (:data:`ANGLE_CONVENTIONS`), deg.

    Returns
    -------
    ProbeReadings

    Raises
    ------
    DataError
        Naming file, line and column of a bad value; naming the file when x, y,
        z look like metres (:mod:`~doe_calib.io.reading_units`).

    Examples
    --------
    >>> probe = read_probe("probe.csv", robot, "rpy")   # doctest: +SKIP
    >>> probe.rotation.shape                            # doctest: +SKIP
    (40, 3, 3)
    """
    if convention not in ANGLE_CONVENTIONS:
        raise DataError(f"unknown angle convention {convention!r}; choose one of "
                        f"{', '.join(ANGLE_CONVENTIONS)}", path)
    table = read_table(path)
    required = ["pose", *joint_columns(robot), *XYZ, *ANGLES]
    missing = [c for c in required if c not in table.columns]
    if missing:
        hint = " (a probe file has one row per pose: x, y, z in mm and angles a, b, c in deg)"
        raise DataError(f"missing column(s) {', '.join(missing)}{hint}", table.path,
                        table.header_line, 1)
    known = set(required) | {*WRENCH, "temperature", "session"}
    for c in table.columns:
        if c not in known:
            raise DataError(f"unknown column {c!r}; accepted columns: {', '.join(required)}, "
                            f"{', '.join(WRENCH)}, temperature, session", table.path,
                            table.header_line, table.col(c))
    problems, notes = RowProblems(table), []
    check_width(table, problems, 0)
    pose = texts(table, problems, 1, "pose", "pose id")
    session = texts(table, problems, 1, "session", default=Path(str(path)).stem)
    wrench = numbers(table, problems, 2, WRENCH, 0.0)
    q = joints(table, problems, 4, robot, LIMIT_TOLERANCE, notes)
    temp = numbers(table, problems, 5, ["temperature"], np.nan)
    position = numbers(table, problems, 6, XYZ) / 1000.0
    angles = numbers(table, problems, 7, ANGLES)
    key = combined([codes(session), codes(pose), *(codes(w + 0.0) for w in wrench.T)])
    first = earlier_in_group(key, ~problems.failing())
    problems.check(3, ~problems.failing(below=3) & (first >= 0), lambda i: (
        f"pose {pose[i]!r} is read twice under the same load (first on line "
        f"{table.numbers[first[i]]}): a probe file has one row per pose and load"), "pose")
    problems.raise_first()
    session = tuple(session)
    cfg = Configurations.from_arrays(q, wrench, temp, pose, derived_approach(q, robot, session))
    # the probe frame sits near the flange: its origin's spread is the flange's, give or take
    # the mount's lever; in metres it is a thousandth of it
    finding = metres_finding(position, robot, q, np.arange(len(q)), np.zeros_like(position),
                             np.array(session))
    if finding is not None:
        raise DataError(finding, table.path)
    return ProbeReadings(cfg, position, angles_to_matrix(angles, convention),
                         np.array(table.numbers), table.path, session,
                         tuple(text for _, text in notes))
