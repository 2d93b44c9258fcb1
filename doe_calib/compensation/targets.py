"""The program to compensate: design-CSV rows, optionally with target positions ``x,y,z``.

A targets CSV is a design CSV (docs/formats.md §4: ``pose``, ``q1``…``qN`` in
deg/mm, optional wrench, temperature and approach columns) that may carry
``x``, ``y``, ``z`` (mm, tracker frame unless a ``frame`` is given: the robot's
``base_link``, the UR controller's ``base``, or any URDF frame fixed to the base,
:mod:`doe_calib.model.frames`): where the TCP must go for that row.
The file is read by :func:`doe_calib.io.csv_files.read_design_csv`, x, y, z with the
design columns.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from doe_calib.errors import OptionError
from doe_calib.io.csv_files import read_design, read_design_csv
from doe_calib.io.measurements import Configurations
from doe_calib.model.frames import frame_placement, transform_points
from doe_calib.model.rotations import rotation_vector_to_matrix

#: The frame target positions are in when none is named: the tracker's, as the readings'.
TRACKER = "tracker"


@dataclass(frozen=True, eq=False)
class Targets:
    """Rows of a program to compensate.

    Attributes
    ----------
    configurations : Configurations
        The programmed q (rad/m) and the wrench carried (N, N·m, base frame) of each row.
    positions : ndarray, shape (M, 3), or None
        Target TCP positions, tracker frame, m; None: where the nominal robot puts the TCP.
    frame : str
        The frame the file gave them in (``tracker`` or a robot frame).
    placement_std : ndarray, shape (M,), or None
        3-D std (m) of each target from the base points' registration, when they placed it.
    """

    configurations: Configurations
    positions: np.ndarray | None = None
    frame: str = TRACKER
    placement_std: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.configurations)


def read_targets(path, robot, frame: str = TRACKER, result=None, base_points=None) -> Targets:
    """Read a targets CSV (design columns, optional ``x,y,z`` in mm).

    Parameters
    ----------
    path : path-like
    robot : Robot
    frame : str
        The frame of ``x,y,z``: ``tracker``, or a robot frame
        (:func:`~doe_calib.model.frames.frame_placement`) placed in the tracker frame by
        ``base_points`` (:func:`~.base_points.read_base_points`) when given, else by
        ``result``'s identified base pose.

    Raises
    ------
    DataError
        Anything :func:`~doe_calib.io.csv_files.read_design` refuses (the file's own line
        and column), only some of ``x,y,z``, or a value there not a finite number.
    OptionError
        A robot ``frame`` without ``result`` or ``base_points``; ``base_points`` with
        targets in the tracker frame or without x, y, z.
    ModelError
        A ``frame`` the URDF does not have (or one moving with a joint).

    Examples
    --------
    >>> targets = read_targets("program.csv", robot)   # doctest: +SKIP
    >>> targets.positions is None                       # doctest: +SKIP
    True
    """
    cfg, xyz = (read_design(path, robot), None) if Path(path).suffix.lower() == ".json" else \
        read_design_csv(path, robot, positions=True)
    if base_points is not None and (frame == TRACKER or xyz is None):
        raise OptionError("base points place targets given in a robot frame: give x, y, z in "
                          "the targets and name their frame (--targets-frame)")
    if xyz is None:
        return Targets(cfg)
    if base_points is not None:
        x_t, std = base_points.to_tracker(xyz)
        return Targets(cfg, x_t, frame, std)
    return Targets(cfg, xyz if frame == TRACKER else in_tracker(xyz, robot, frame, result), frame)


def in_tracker(points, robot, frame: str, result) -> np.ndarray:
    """Points (K, 3) m given in the robot frame ``frame``, in the tracker frame:
    ``R_b (T_frame p) + t_b`` with ``(R_b, t_b)`` the base pose ``result`` identified."""
    if result is None:
        raise OptionError(f"targets in frame {frame!r} need the identification result (its base "
                          f"pose places the robot in the tracker frame)")
    base = result.parameters.values[result.parameters.index("base")]
    in_base = transform_points(frame_placement(robot, frame), points)
    return in_base @ rotation_vector_to_matrix(base[3:]).T + base[:3]
