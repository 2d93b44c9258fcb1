"""Reading and writing the users' files: measurement CSV and design CSV (formats.md §3, §4).

Files are in controller and tracker units (deg, mm, N, N·m, °C); everything
returned is SI. The first bad value of a file raises :class:`~doe_calib.errors.DataError`
naming the file, the physical line and the column; with ``skip_bad`` every bad
row is dropped instead and reported in ``Measurements.dropped``. Whole columns
are converted and checked at once (:mod:`~doe_calib.io.configuration_columns`).

Files are UTF-8 (a bad byte is reported with its line and column); fields are
separated by commas, or by semicolons or tabs as the header shows, and then a
number may have a decimal comma (``1,5``). Values outside a plausible range
(:data:`~doe_calib.io.configuration_columns.PLAUSIBLE`: a temperature outside
-50 … 150 °C) are errors.

Approach directions (for ``backlash``): the optional columns ``approach1``
… ``approachN`` give, for each row, the direction from which joint k reached
the pose: ``1`` (or ``+1``; moving up, q increasing), ``-1`` (moving down) or
``0`` (unknown); any other value is an error. Give all N columns or none.
When they are absent, the directions come from the measurement order: the
configurations, in order of first appearance in the file, are taken to be
visited in that order, so configuration i gets ``sign(q_k(i) − q_k(i−1))``
for joint k, the previous configuration's direction when joint k did not move
(the same pose under another load, or a joint held still), and 0 for the
first configuration. With the columns, rows of one pose and load that differ
in approach are different configurations (a pose measured from both sides).

Writers put the approach columns in only when reading the file back would
not derive the same directions from its order, so every measurement file
round-trips exactly. A design whose directions are all 0 (not planned: the
design algorithms cannot plan them) is written without them; reading it
back then derives the directions the robot will have running the design in
the file's order.
"""
from __future__ import annotations

import csv
import io as _io
import warnings
from pathlib import Path

import numpy as np

from doe_calib.errors import DataError, DataWarning
from doe_calib.io.configuration_columns import (
    LIMIT_TOLERANCE,
    Q_TOL,
    WRENCH,
    XYZ,
    approach,
    approach_columns,
    approach_given,
    check_columns,
    check_not_radians,
    check_width,
    codes,
    combined,
    derived_approach,
    ignored_note,
    joint_columns,
    joints,
    numbers,
    texts,
)
from doe_calib.io.design_json import read_design_json
from doe_calib.io.logged_turns import TURN_DEG, TURN_TOLERANCE, turns_note, whole_turns
from doe_calib.io.measurements import (
    ESTIMATED,
    GIVEN,
    MIN_TOUCHES,
    PER_READING,
    Configurations,
    Measurements,
)
from doe_calib.io.reading_units import metres_finding
from doe_calib.io.row_problems import RowProblems, earlier_in_group
from doe_calib.io.table import read_table

#: Columns of a given plane's normal (formats.md §3, *Plane touches*); unit-free, normalised.
NORMAL = ("nx", "ny", "nz")
#: Columns ``doe-calib predict`` adds: predicted std of each coordinate (mm); ignored on reading.
PREDICTED_STD = ("std_x", "std_y", "std_z")


def read_measurements(path, robot, tool, sigma: float | None = None, skip_bad: bool = False,
                      require_xyz: bool = True, session: str | None = None) -> Measurements:
    """Read a measurement CSV (formats.md §3).

    Parameters
    ----------
    path : path-like
    robot : Robot
        Gives N (columns q1..qN, deg or mm) and the joint limits.
    tool : Tool
        Gives the marker names.
    sigma : float, optional
        σ (m) of the readings without a ``sigma`` value of their own. With
        neither, σ is not given: ``sigma`` is NaN and ``sigma_estimated`` is
        set; :func:`~doe_calib.estimation.sigma.resolve_sigma` decides it.
    skip_bad : bool
        Drop bad rows, reporting each in ``dropped``, instead of raising.
    require_xyz : bool
        False to accept files without x, y, z (positions are then NaN).
    session : str, optional
        Session name of rows without a ``session`` column value (default: the
        file's name without extension).

    Returns
    -------
    Measurements
        In SI; configurations keyed by (pose, wrench, temperature, session and
        the approach directions when given) in order of first appearance;
        without approach columns the directions come from that order, session
        by session (module notes). A joint value past its limit by at most
        :data:`~doe_calib.io.configuration_columns.LIMIT_TOLERANCE` of the range
        is kept, with a message in ``warnings``.

    Raises
    ------
    DataError
        Naming file, line and column of the first bad value; naming the file when
        x, y, z look like metres (their spread ~1/1000 of the one the nominal robot
        gives these joint values: :mod:`~doe_calib.io.reading_units`).

    Examples
    --------
    >>> meas = read_measurements("meas.csv", robot, tool)   # doctest: +SKIP
    >>> meas.sigma_source                                    # doctest: +SKIP
    'per reading'
    """
    table = read_table(path)
    contacts = bool({"socket", "plane"} & set(table.columns))  # x, y, z empty on their rows
    tracked_xyz, require_xyz = require_xyz, require_xyz and not contacts
    required = ["pose", *joint_columns(robot), "marker", *(XYZ if require_xyz else ())]
    optional = [*WRENCH, "temperature", "sigma", "session", "socket", "socket_sigma", "plane",
                "distance", *approach_columns(robot), *(() if require_xyz else XYZ),
                *NORMAL, *PREDICTED_STD]
    extra = check_columns(table, required, optional)
    explicit = approach_given(table, robot)
    if sigma is not None and not sigma > 0:
        raise DataError(f"σ must be positive, got {sigma * 1000.0} mm", table.path)
    table.cells(["pose", "marker", "session", "socket", "plane"])  # each kind in one pass
    table.floats([*joint_columns(robot), *WRENCH, "temperature", "sigma", *XYZ, "distance",
                  "socket_sigma", *NORMAL, *approach_columns(robot)])
    problems, notes = RowProblems(table), []
    check_width(table, problems, 0)
    pose = texts(table, problems, 1, "pose", "pose id")
    sessions = texts(table, problems, 2, "session", "session name",
                     session or Path(str(path)).stem)
    names = texts(table, problems, 3, "marker")
    index = {name: i for i, name in enumerate(tool.names)}
    marker = np.array([index.get(m, -1) for m in names], int)
    problems.check(3, marker < 0, lambda i: f"marker {names[i]!r} is not in the tool file "
                                            f"(markers: {', '.join(tool.names)})", "marker")
    q = joints(table, problems, 4, robot, LIMIT_TOLERANCE, notes)
    wrench = numbers(table, problems, 6, WRENCH, 0.0)
    temp = numbers(table, problems, 7, ["temperature"], np.nan)[:, 0]
    sig = numbers(table, problems, 8, ["sigma"], None if sigma is None else np.nan)[:, 0]
    problems.check((8, 9), ~np.isnan(sig) & ~(sig > 0), lambda i: f"σ must be positive, got "
                                                               f"{sig[i]}", "sigma")
    sigma_m = np.where(np.isnan(sig), np.nan if sigma is None else sigma, sig / 1000.0)
    xyz = numbers(table, problems, 9, XYZ, None if require_xyz else np.nan) / 1000.0
    socket_ids = texts(table, problems, 9, "socket") if contacts else None
    plane_ids = texts(table, problems, 9, "plane") if contacts else None
    distance = numbers(table, problems, 8.9, ["distance"], np.nan)[:, 0] / 1000.0
    drawn = numbers(table, problems, 9.5, ["socket_sigma"], 0.0)[:, 0] / 1000.0
    normal = numbers(table, problems, 9.5, list(NORMAL), np.nan)
    if contacts:
        _check_contacts(table, problems, socket_ids, plane_ids, xyz, tracked_xyz)
        _check_given_planes(table, problems, plane_ids, xyz, normal)
        _check_socket_sigma(table, problems, socket_ids, xyz, drawn)
    _check_distances(table, problems, socket_ids, distance)
    problems.check((9, 19, 1), np.isfinite(distance) & np.isfinite(xyz).any(axis=1), lambda i: (
        "distance with x, y, z: a ballbar's pivot is a socket of unknown position; leave "
        "x, y, z empty"), "distance")
    appr = approach(table, problems, 10, robot) if explicit else None
    pose_code, session_code = codes(pose), codes(sessions)
    turns = _same_q(table, problems, 5, robot, q, combined([session_code, pose_code]), pose)
    key = combined([pose_code, *(codes(w + 0.0) for w in wrench.T),
                    codes(np.where(np.isfinite(temp), temp + 0.0, np.inf)),
                    *(codes(a) for a in (appr.T if explicit else ())), session_code,
                    *(codes(t) for t in turns.T if t.any())])
    read = ~problems.failing()
    first = earlier_in_group(combined([key, codes(marker)]), read)
    problems.check(11, read & (first >= 0), lambda i: (
        f"marker {names[i]!r} is read twice in pose {pose[i]!r} under the same load (first on "
        f"line {table.numbers[first[i]]})"), "marker")
    if contacts:
        _check_counts(table, problems, socket_ids,
                      [c if not np.isfinite(n[0]) else "" for c, n in zip(plane_ids, normal)],
                      distance)
    if not skip_bad:
        problems.raise_first()
    dropped = problems.dropped()
    rows = np.flatnonzero(~problems.failing())
    if not rows.size:
        raise DataError("no valid data rows", table.path)
    _, first_row, config = np.unique(key[rows], return_index=True, return_inverse=True)
    order = np.argsort(first_row)  # configurations in order of first appearance
    config, first_row = np.argsort(order)[config].reshape(-1), rows[first_row[order]]
    check_not_radians(q[first_row], robot, table.path)
    session = tuple(sessions[r] for r in first_row.tolist())
    cfg = Configurations.from_arrays(q[first_row], wrench[first_row], temp[first_row, None],
                                     [pose[r] for r in first_row.tolist()],
                                     appr[first_row] if explicit else
                                     derived_approach(q[first_row], robot, session))
    given = not np.isnan(sigma_m).any()
    kept = set(rows.tolist())
    turned = turns_note(pose, turns, rows)
    notes = ([(-1, turned)] if turned else []) + notes
    meas = Measurements(cfg, config, marker[rows], xyz[rows], sigma_m[rows],
                        np.array(table.numbers)[rows], table.path, dropped,
                        ((ignored_note(table, extra),) if extra else ())
                        + tuple(text for i, text in notes if i in kept or i < 0),
                        session, not given,
                        PER_READING if "sigma" in table.columns else GIVEN if given else ESTIMATED,
                        **(_without_coordinates(socket_ids, plane_ids, distance, rows)
                           if contacts else {}),
                        socket_sigma=drawn[rows] if contacts and np.any(drawn > 0) else None,
                        plane_normal=_unit(normal[rows]) if np.isfinite(normal).any() else None)
    tracked = meas.subset(~meas.contact) if contacts else meas  # the tracker's readings
    finding = metres_finding(tracked.xyz, robot, tracked.configurations.q, tracked.config,
                             tool.position_array[tracked.marker],
                             tracked.sessions[tracked.config])
    if finding is not None:
        raise DataError(finding, meas.source)
    return meas


def _check_contacts(table, problems, socket_ids, plane_ids, xyz, tracked_xyz: bool) -> None:
    """Refuse a contact (a ``socket`` id) with some of x, y, z, or other x, y, z than the
    socket's first contact (all rows of a socket give its one known position, or none), a
    touch (a ``plane`` id) with x, y, z, a row with both ids and, with ``tracked_xyz``, a
    tracker reading (no id) without all three (formats.md §3, *Socket contacts*, *Plane
    touches*)."""
    seated = np.array([bool(c) for c in socket_ids])
    touch = np.array([bool(c) for c in plane_ids])
    given = np.isfinite(xyz)
    column = "x" if "x" in table.columns else "socket"
    problems.check((9, 20), seated & given.any(axis=1) & ~given.all(axis=1), lambda i: (
        f"socket {socket_ids[i]!r} with some of x, y, z: give all three (the socket's known "
        f"position, mm) or none (its position unknown)"), column)
    first = earlier_in_group(codes(socket_ids), seated)
    f = np.maximum(first, 0)
    same = np.all(np.where(given & given[f], np.abs(xyz - xyz[f]) <= 1e-9, given == given[f]),
                  axis=1)
    problems.check((9, 20, 1), seated & (first >= 0) & ~same, lambda i: (
        f"socket {socket_ids[i]!r} at {_at_mm(xyz[i])} here but {_at_mm(xyz[first[i]])} on "
        f"line {table.numbers[first[i]]}: every contact of a socket gives the same x, y, z "
        f"(its known position, mm) or none (unknown)"), column)
    problems.check((9, 20), seated & touch, lambda i: (
        f"socket {socket_ids[i]!r} and plane {plane_ids[i]!r} on one row: a row is a socket "
        f"contact or a plane touch"), "plane")
    problems.check((9, 21), tracked_xyz & ~seated & ~touch & ~given.all(axis=1), lambda i: (
        "x, y, z missing on a row without a socket: give the tracker reading, or the socket "
        "id of a contact" + (" (or the plane id of a touch)" if "plane" in table.columns
                             else "")), "x" if "x" in table.columns else "socket")

def _check_given_planes(table, problems, plane_ids, xyz, normal) -> None:
    """Refuse a touch with some but not all of x, y, z, nx, ny, nz (a point of its plane and
    its normal: all six give the plane's position, none leave it unknown), a zero normal,
    other numbers than on the plane's first touch, and a normal on a row that is no touch
    (formats.md §3, *Plane touches*)."""
    touch = np.array([bool(c) for c in plane_ids])
    cells = np.c_[xyz * 1000.0, normal]
    given = np.isfinite(cells)
    names = [*XYZ, *NORMAL]
    for k, column in enumerate(names):
        problems.check((9, 20, 2), touch & given.any(axis=1) & ~given[:, k], lambda i: (
            f"plane {plane_ids[i]!r} with some of x, y, z, nx, ny, nz: give all six (a point "
            f"of the plane, mm, and its normal) or none (its position unknown)"), column)
    problems.check((9, 20, 3), touch & given.all(axis=1) & ~(np.abs(normal) > 0).any(axis=1),
                   lambda i: f"plane {plane_ids[i]!r} with a zero normal (nx, ny, nz)", "nx")
    first = earlier_in_group(codes(plane_ids), touch)
    f = np.maximum(first, 0)
    for k, column in enumerate(names):
        differ = np.where(given[:, k] & given[f, k], np.abs(cells[:, k] - cells[f, k]) > 1e-9,
                          given[:, k] != given[f, k])
        problems.check((9, 20, 4), touch & (first >= 0) & differ, lambda i, k=k, c=column: (
            f"plane {plane_ids[i]!r} with {c} {_cell(cells[i, k])} here but "
            f"{_cell(cells[first[i], k])} on line {table.numbers[first[i]]}: every touch of a "
            f"plane gives the same x, y, z, nx, ny, nz (its known position) or none "
            f"(unknown)"), column)
    problems.check((9, 20, 5), ~touch & given[:, 3:].any(axis=1), lambda i: (
        "nx, ny, nz on a row without a plane: they give a touched plane's normal"), "nx")


def _cell(value) -> str:
    return "empty" if np.isnan(value) else f"{value:g}"


def _unit(normal) -> np.ndarray:
    """Rows of ``normal`` (K, 3) scaled to unit length (NaN rows stay NaN)."""
    return normal / np.linalg.norm(normal, axis=1, keepdims=True)


def _at_mm(xyz) -> str:
    """A socket's position (3,), m, as the file gives it, mm, or "no x, y, z"."""
    return "no x, y, z" if np.isnan(xyz).all() else \
        f"({', '.join(f'{v * 1000.0:g}' for v in xyz)}) mm"



def _check_distances(table, problems, socket_ids, distance) -> None:
    """Refuse a negative ballbar length and one without its pivot's socket id
    (formats.md §3, *Ballbar and gauge lengths*)."""
    given = np.isfinite(distance)
    problems.check((9, 18), given & (distance < 0), lambda i: (
        f"distance {distance[i] * 1000.0:g} mm: a ballbar's length is positive (empty or 0 "
        f"for a contact seated in its socket)"), "distance")
    pivot = np.zeros(len(distance), bool) if socket_ids is None else \
        np.array([bool(c) for c in socket_ids])
    problems.check((9, 19), given & ~pivot, lambda i: (
        "distance without a socket: a ballbar's length is measured from its pivot, whose id "
        "goes in the socket column"), "distance")


def _check_counts(table, problems, socket_ids, plane_ids, distance) -> None:
    """Refuse, of the rows read, the touches of a plane with fewer than :data:`MIN_TOUCHES`
    and the ballbar readings of a pivot with fewer than 4 and no seated contact: such a
    plane or pivot takes all its readings to place."""
    read = ~problems.failing()
    bar = np.isfinite(distance) & (distance > 0)
    for ids, what, kind, rows_of in ((plane_ids, "touches", "plane", lambda at: at),
                                     (socket_ids, "ballbar readings", "socket",
                                      lambda at: at if bar[at].all() else at[:0])):
        groups = {}
        for i in np.flatnonzero(read).tolist():
            if ids[i]:
                groups.setdefault(ids[i], []).append(i)
        for name, at in groups.items():
            at = rows_of(np.array(at))
            if 0 < len(at) < MIN_TOUCHES:
                bad = np.zeros(len(read), bool)
                bad[at] = True
                lines = ", ".join(str(table.numbers[i]) for i in at.tolist())
                problems.check(12, bad, lambda i, said=f"{kind} {name!r} has {len(at)} {what} "
                               f"(lines {lines})": (
                                   f"{said}: its unknown point or plane takes 3 to place; "
                                   f"give it {MIN_TOUCHES} or more"), kind)


def _check_socket_sigma(table, problems, socket_ids, xyz, drawn) -> None:
    """Refuse a ``socket_sigma`` (the std of a socket's given position, m) that is negative,
    on a row without a socket's given x, y, z, or other than on the socket's first row."""
    given = np.array([bool(c) for c in socket_ids]) & np.isfinite(xyz).all(axis=1)
    problems.check((9, 23), drawn < 0, lambda i: (
        f"socket_sigma {drawn[i] * 1000.0:g} mm: a position's std is 0 or more"), "socket_sigma")
    problems.check((9, 24), (drawn > 0) & ~given, lambda i: (
        "socket_sigma on a row without a socket's given x, y, z: it is the std of a given "
        "socket position"), "socket_sigma")
    first = earlier_in_group(codes(socket_ids), given)
    problems.check((9, 25), given & (first >= 0) & (drawn != drawn[np.maximum(first, 0)]),
                   lambda i: (f"socket {socket_ids[i]!r} with socket_sigma "
                              f"{drawn[i] * 1000.0:g} mm here but "
                              f"{drawn[first[i]] * 1000.0:g} mm on line "
                              f"{table.numbers[first[i]]}: one std per socket"),
                   "socket_sigma")


def _without_coordinates(socket_ids, plane_ids, distance, rows) -> dict:
    """The fields of :class:`Measurements` for the readings ``rows`` without coordinates,
    from each row's socket and plane id ("" for neither) and ballbar length (m, NaN)."""
    out = {}
    for kind, ids in (("socket", socket_ids), ("plane", plane_ids)):
        kept = [ids[r] for r in rows.tolist()]
        names = tuple(dict.fromkeys(i for i in kept if i))
        at = {n: k for k, n in enumerate(names)}
        if names or kind == "socket":
            out.update({kind: np.array([at.get(i, -1) for i in kept], int),
                        f"{kind}_names": names})
    lengths = np.where(distance[rows] > 0, distance[rows], np.nan)
    if np.isfinite(lengths).any():
        out["distance"] = lengths
    return out


def _same_q(table, problems, rank, robot, q, group, pose) -> np.ndarray:
    """Refuse a row whose q differs from that of the first good row of its pose (``group``)
    other than by whole turns (:mod:`~doe_calib.io.logged_turns`); return those turns (R, N)."""
    shown = q * robot.display_factors
    first = earlier_in_group(group, ~problems.failing())
    checked = ~problems.failing(below=rank) & (first >= 0)
    apart = shown - shown[np.maximum(first, 0)]
    turns = np.where(checked[:, None], whole_turns(apart, robot), 0)
    differ = np.abs(apart - TURN_DEG * turns) > np.where(turns != 0, TURN_TOLERANCE, Q_TOL)
    which = np.argmax(differ, axis=1)
    for k, name in enumerate(joint_columns(robot)):
        problems.check((rank, k), checked & differ.any(axis=1) & (which == k), lambda i, k=k: (
            f"pose {pose[i]!r} has q{k + 1} = {shown[i, k]:g} here but {shown[first[i], k]:g} "
            f"on line {table.numbers[first[i]]}; all rows of a pose share q (or differ by "
            f"whole turns on a joint of more than a turn)"), name)
    return turns


def read_design(path, robot) -> Configurations:
    """Read a design (formats.md §4): the CSV, or the JSON ``doe-calib design`` writes.

    CSV: pose, q1..qN (deg/mm), optional wrench, temperature, and optional
    ``approach1`` … ``approachN`` columns as in a measurement file; without
    them the directions come from the row order (module notes), as for the
    poses of a JSON design (where a pose plans no direction for a joint). A
    JSON design must be for ``robot``'s joints.
    """
    if Path(path).suffix.lower() == ".json":
        cfg = read_design_json(path, robot)
        approach_ = np.where(cfg.approach != 0, cfg.approach, derived_approach(cfg.q, robot))
        return Configurations.from_arrays(cfg.q, cfg.wrench, pose=cfg.pose, approach=approach_)
    return read_design_csv(path, robot)[0]


def read_design_csv(path, robot, positions: bool = False) -> tuple:
    """A design CSV's configurations and, with ``positions``, its optional columns x, y, z.

    Returns
    -------
    (Configurations, ndarray or None)
        The configurations, and the positions (M, 3) in m, or None when the file has
        no x, y, z (or ``positions`` is False).

    Raises
    ------
    DataError
        The first bad value, with file, line and column; some of x, y, z but not all.
    """
    table = read_table(path)
    given = [c for c in XYZ if positions and c in table.columns]
    if given and len(given) < 3:
        missing = ", ".join(c for c in XYZ if c not in given)
        raise DataError(f"target column(s) {', '.join(given)} without {missing}: give all "
                        f"of x, y, z (mm, tracker frame) or none", path, table.header_line)
    extra = check_columns(table, ["pose", *joint_columns(robot), *given],
                          [*WRENCH, "temperature", *approach_columns(robot)])
    if extra:  # the design's configurations have no place for notes
        warnings.warn(ignored_note(table, extra), DataWarning, stacklevel=3)
    explicit = approach_given(table, robot)
    problems = RowProblems(table)
    check_width(table, problems, 0)
    pose = texts(table, problems, 1, "pose", "pose id")
    q = joints(table, problems, 2, robot)
    wrench = numbers(table, problems, 3, WRENCH, 0.0)
    temp = numbers(table, problems, 4, ["temperature"], np.nan)
    appr = approach(table, problems, 5, robot) if explicit else None
    xyz = numbers(table, problems, 6, given) / 1000.0 if given else None
    problems.raise_first()
    check_not_radians(q, robot, table.path)
    return (Configurations.from_arrays(q, wrench, temp, pose,
                                       appr if explicit else derived_approach(q, robot)), xyz)


def _numbers(names, values, unknown_empty: bool = False) -> dict:
    """Columns ``names`` of ``values`` (R, len(names)) as text that reads back exactly;
    with ``unknown_empty`` a NaN (not known) is an empty cell."""
    return {name: [repr(float(v)) if not unknown_empty or np.isfinite(v) else "" for v in col]
            for name, col in zip(names, np.asarray(values, float).T)}


def _configuration_columns(cfg, c, robot) -> dict:
    """Columns pose, q1..qN (deg, mm) and the wrench of configurations ``c`` (R,), one row each."""
    return {"pose": [cfg.pose[i] for i in c],
            **_numbers(joint_columns(robot), cfg.q[c] * robot.display_factors),
            **_numbers(WRENCH, cfg.wrench[c])}


def _write(path, comment, columns: dict) -> None:
    """A CSV of ``columns`` (name → cells, one per row) below the line ``# comment``."""
    buf = _io.StringIO()
    buf.write(f"# {comment}\n")
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    writer.writerows(zip(*columns.values()))
    Path(path).write_text(buf.getvalue(), encoding="utf-8")


def _approach_needed(cfg, order, robot) -> bool:
    """Whether the file needs the approach columns to read back as ``cfg``.

    They are needed when the directions differ from those derived when
    visiting ``order``, or to tell apart configurations that share pose,
    load and temperature (one pose reached from both sides).
    """
    approach = cfg.approach[order]
    keys = {(cfg.pose[c], tuple(cfg.wrench[c]), np.nan_to_num(cfg.temperature[c], nan=np.inf))
            for c in order}
    return len(keys) < len(order) or \
        not np.array_equal(approach, derived_approach(cfg.q[order], robot))


def _approach_cells(cfg, c, robot) -> dict:
    return dict(zip(approach_columns(robot), cfg.approach[c].astype(int).astype(str).T.tolist()))


def write_measurements(path, measurements, robot, tool, std=None) -> None:
    """Write readings as a measurement CSV (deg/mm, mm, N, N·m), exactly re-readable.

    The approach columns are written only when reading back would not derive
    the same directions from the order of the rows (module notes); the
    ``session`` column only when the readings come from several sessions; the
    ``sigma`` column only when some reading has a σ; the ``socket``, ``plane``,
    ``distance`` and ``socket_sigma`` columns only when some reading has one. ``std``
    (K, 3), m: a prediction's standard deviation of each coordinate, written as the
    :data:`PREDICTED_STD` columns in mm (ignored on reading).
    """
    cfg, c, sessions = measurements.configurations, measurements.config, measurements.sessions
    order = np.array(list(dict.fromkeys(c.tolist())), int)  # in order of first appearance
    columns = {**_configuration_columns(cfg, c, robot),
               "marker": [tool.names[j] for j in measurements.marker],
               **_numbers(XYZ, measurements.xyz * 1000.0,
                          unknown_empty=bool(measurements.contact.any()))}
    columns.update(_contact_cells(measurements))
    if np.isfinite(cfg.temperature).any():
        columns.update(_numbers(["temperature"], cfg.env[c, :1], unknown_empty=True))
    if not np.isnan(measurements.sigma).all():  # none given: none written
        columns.update(_numbers(["sigma"], measurements.sigma[:, None] * 1000.0,
                                unknown_empty=True))
    if _approach_needed(cfg, order, robot):
        columns.update(_approach_cells(cfg, c, robot))
    if len(set(sessions)) > 1:
        columns["session"] = [sessions[i] for i in c]
    if std is not None:
        columns.update(_numbers(PREDICTED_STD, np.asarray(std, float) * 1000.0))
    _write(path, "doe_calib measurements: q in deg (mm for prismatic joints), x/y/z and sigma "
                 "in mm, forces in N, moments in N·m, temperature in °C", columns)


def _contact_cells(measurements) -> dict:
    """The columns ``socket``, ``plane`` and ``distance`` (mm) of the readings that have them
    (formats.md §3), empty cells for the other rows; none without such readings."""
    out = {}
    for kind in ("socket", "plane"):
        index, names = getattr(measurements, kind), getattr(measurements, f"{kind}_names")
        if index is not None and (index >= 0).any():
            out[kind] = [names[k] if k >= 0 else "" for k in index.tolist()]
    if measurements.ballbar.any():
        out.update(_numbers(["distance"], measurements.distance[:, None] * 1000.0,
                            unknown_empty=True))
    if measurements.socket_sigma is not None:
        out.update(_numbers(["socket_sigma"], measurements.socket_sigma[:, None] * 1000.0))
    if measurements.plane_normal is not None:
        out.update(_numbers(NORMAL, measurements.plane_normal, unknown_empty=True))
    return out


def write_design(path, configurations, robot) -> None:
    """Write configurations as a design CSV (formats.md §4).

    The approach columns are written only when some direction is planned (not
    0) and reading back would not derive the same from the row order.
    """
    cfg, c = configurations, np.arange(len(configurations))
    columns = _configuration_columns(cfg, c, robot)
    if np.isfinite(cfg.temperature).any():
        columns.update(_numbers(["temperature"], cfg.env[:, :1], unknown_empty=True))
    if np.any(cfg.approach != 0) and _approach_needed(cfg, c, robot):
        columns.update(_approach_cells(cfg, c, robot))
    _write(path, "doe_calib design: q in deg (mm for prismatic joints), forces in N, moments "
                 "in N·m", columns)
