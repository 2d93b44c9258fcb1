"""The program to compensate: design-CSV rows, optionally with target positions ``x,y,z``.

A targets CSV is a design CSV (docs/formats.md §4) that may carry ``x``, ``y``, ``z``
(mm, tracker frame unless a robot ``frame`` is given, :mod:`doe_calib.model.frames`):
where the TCP must go for that row. This module reads those three columns and hands
:func:`doe_calib.io.csv_files.read_design` the file without them, line numbers kept.
"""
from __future__ import annotations

import csv
import io
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from doe_calib.errors import DataError, OptionError
from doe_calib.io.columns import XYZ
from doe_calib.io.csv_files import read_design
from doe_calib.io.measurements import Configurations
from doe_calib.io.table import read_table
from doe_calib.model.frames import frame_placement, transform_points
from doe_calib.model.rotations import rotation_vector_to_matrix

#: The frame target positions are in when none is named (as they always were).
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


def _split_line(line: str, delimiter: str, drop: list) -> str:
    """``line`` without the fields at ``drop`` (quoted fields kept whole)."""
    fields = next(csv.reader([line], delimiter=delimiter))
    buf = io.StringIO()
    csv.writer(buf, delimiter=delimiter, lineterminator="").writerow(
        [f for i, f in enumerate(fields) if i not in drop])
    return buf.getvalue()


def _renumber(message_column, columns, kept):
    """A DataError column ``'q3' (4)`` of the stripped file as a column of the original."""
    if not isinstance(message_column, str):
        return message_column if message_column is None else kept[message_column - 1] + 1
    match = re.fullmatch(r"'(.*)' \((\d+)\)", message_column)
    if match and match.group(1) in columns:
        return f"'{match.group(1)}' ({columns.index(match.group(1)) + 1})"
    return message_column


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
    table = read_table(path)
    present = [c for c in XYZ if c in table.columns]
    if base_points is not None and (frame == TRACKER or not present):
        raise OptionError("base points place targets given in a robot frame: give x, y, z in "
                          "the targets and name their frame (--targets-frame)")
    if not present:
        return Targets(read_design(path, robot))
    header_line = table.rows[0][0] - 1
    if len(present) < 3:
        missing = ", ".join(c for c in XYZ if c not in present)
        raise DataError(f"target column(s) {', '.join(present)} without {missing}: give all "
                        f"of x, y, z (mm, tracker frame) or none", path, header_line)
    drop = [table.columns.index(c) for c in XYZ]
    kept = [i for i in range(len(table.columns)) if i not in drop]
    xyz = np.empty((len(table.rows), 3))
    for r, (line, fields) in enumerate(table.rows):
        for a, c in enumerate(XYZ):
            text = fields[drop[a]] if drop[a] < len(fields) else ""
            try:
                value = float(text.replace(",", ".") if table.decimal_comma else text)
            except ValueError:
                raise DataError(f"{text!r} is not a number (target {c} in mm)", path, line,
                                table.col(c)) from None
            if not np.isfinite(value):
                raise DataError(f"{text!r} is not a finite number", path, line, table.col(c))
            xyz[r, a] = value / 1000.0
    sep = table.separator
    text = Path(path).read_text(encoding="utf-8-sig")
    lines = [ln if not ln.strip() or ln.lstrip().startswith("#") else
             _split_line(ln, sep, drop) for ln in text.splitlines()]
    with tempfile.TemporaryDirectory() as tmp:
        stripped = Path(tmp) / Path(path).name
        stripped.write_text("\n".join(lines) + "\n", encoding="utf-8")
        try:
            cfg = read_design(stripped, robot)
        except DataError as exc:
            raise DataError(_message(exc), path, exc.line,
                            _renumber(exc.column, table.columns, kept)) from None
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


def _message(exc: DataError) -> str:
    """The message of a DataError without its ``path, line, column:`` prefix."""
    where = DataError("", exc.path, exc.line, exc.column)
    return str(exc)[len(str(where)):]

