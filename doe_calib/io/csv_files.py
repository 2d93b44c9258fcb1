"""Reading and writing the users' files: measurement CSV and design CSV (formats.md §3, §4).

Files are in controller and tracker units (deg, mm, N, N·m, °C); everything
returned is SI. Every problem raises :class:`~doe_calib.errors.DataError`
naming the file, the physical line and the column; with ``skip_bad`` a bad
row is dropped instead and reported in ``Measurements.dropped``.

Files are UTF-8 (a bad byte is reported with its line and column); fields are
separated by commas, or by semicolons or tabs as the header shows, and then a
number may have a decimal comma (``1,5``). Values outside a plausible range
(:data:`PLAUSIBLE`: a temperature outside -50 … 150 °C) are errors.

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
import re
import warnings
from difflib import get_close_matches
from pathlib import Path

import numpy as np

from doe_calib.errors import DataError, DataWarning
from doe_calib.io.column_reader import Columns, read_columns
from doe_calib.io.gc_paused import gc_paused
from doe_calib.io.columns import PLAUSIBLE, Q_TOL, WRENCH, XYZ, approach_columns, joint_columns
from doe_calib.io.measurements import (
    ESTIMATED,
    GIVEN,
    PER_READING,
    Configurations,
    Measurements,
    approach_from_order,
)
from doe_calib.io.table import Table, read_table

#: σ (mm) of the readings of a file without σ, until identification estimates it.
PROVISIONAL_SIGMA_MM = 1.0
#: Columns ``doe-calib predict`` adds: predicted std of each coordinate (mm); ignored on reading.
PREDICTED_STD = ("std_x", "std_y", "std_z")


#: Columns that look like doe_calib's own (a joint or approach column of another robot).
_OWN_PATTERN = re.compile(r"^(q|approach)\d+$")
#: difflib similarity above which an unknown column is taken for a typo of a known one.
TYPO_CUTOFF = 0.75


def _check_columns(table: Table, required, optional, line) -> tuple:
    """Refuse missing columns and typos of known ones; return the other extra columns.

    An unknown column is an error when it looks like a known one (a close
    match, e.g. ``sigam`` for ``sigma``, or a joint column the robot does not
    have); any other (``timestamp``) is ignored and returned for a note.
    """
    missing = [c for c in required if c not in table.columns]
    if missing:
        raise DataError(f"missing column(s) {', '.join(missing)}; the header must hold "
                        f"{', '.join(required)}", table.path, line, 1)
    accepted = list(required) + list(optional)
    known = {c.lower(): c for c in accepted}
    extra = []
    for i, c in enumerate(table.columns):
        if c in accepted:
            continue
        close = get_close_matches(c.lower(), list(known), n=1, cutoff=TYPO_CUTOFF)
        if close or _OWN_PATTERN.match(c.lower()):
            hint = (f"did you mean {known[close[0]]!r}?" if close else
                    "the robot has no such joint")
            raise DataError(f"unknown column {c!r} ({hint}); accepted columns: "
                            f"{', '.join(accepted)}", table.path, line, f"'{c}' ({i + 1})")
        extra.append(c)
    return tuple(extra)


def _ignored_note(table, extra) -> str:
    return (f"{table.path}: column(s) {', '.join(repr(c) for c in extra)} ignored (not "
            "doe_calib columns; docs/formats.md §3 lists them)")


def _number(table, line, fields, name, default=None) -> float:
    if name not in table.columns:
        return default
    text = fields[table.columns.index(name)]
    if text == "" and default is not None:
        return default
    try:
        value = float(text.replace(",", ".") if table.decimal_comma else text)
    except ValueError:
        raise DataError(f"{text!r} is not a number", table.path, line, table.col(name)) from None
    if not np.isfinite(value):
        raise DataError(f"{text!r} is not a finite number", table.path, line, table.col(name))
    _check_plausible(table, line, name, value)
    return value


def _check_plausible(table, line, name, value) -> None:
    """Refuse a value outside the :data:`PLAUSIBLE` range of its column."""
    if name in PLAUSIBLE:
        low, high, unit = PLAUSIBLE[name]
        if not low <= value <= high:
            raise DataError(f"{value:g} {unit} is not a plausible {name}: expected {low:g} to "
                            f"{high:g} {unit}", table.path, line, table.col(name))


def _checkapproach_columns(table, robot, line) -> bool:
    """Whether the file gives the approach directions (all N columns; some is an error)."""
    names = approach_columns(robot)
    present = [c for c in names if c in table.columns]
    if present and len(present) < len(names):
        missing = [c for c in names if c not in table.columns]
        raise DataError(f"approach column(s) {', '.join(missing)} missing: give all of "
                        f"{names[0]} … {names[-1]} or none (then they come from the "
                        f"measurement order)", table.path, line, table.col(present[0]))
    return bool(present)


def _approach(table, line, fields, robot) -> tuple:
    """Approach direction of each joint in one row: +1, −1 or 0."""
    out = []
    for name in approach_columns(robot):
        text = fields[table.columns.index(name)]
        try:
            value = float(text)
        except ValueError:
            value = None
        if value not in (-1.0, 0.0, 1.0):
            raise DataError(f"{text!r} is not an approach direction: write 1 (joint moving up), "
                            f"-1 (moving down) or 0 (unknown)", table.path, line, table.col(name))
        out.append(value + 0.0)  # no -0.0
    return tuple(out)


def _derived_approach(q, robot) -> np.ndarray:
    """Approach directions from the visiting order of configurations q (M, N), SI."""
    return approach_from_order(np.asarray(q) * robot.display_factors, Q_TOL)


#: A measured joint value past a URDF limit by at most this fraction of the joint's range
#: is accepted with a warning (an encoder at a hard stop, a rounded limit); farther is an error.
LIMIT_TOLERANCE = 0.02


def _joints(table, line, fields, robot, tolerance: float = 0.0, notes=None) -> np.ndarray:
    """q of one row in SI, checked against the limits.

    A value past a limit by at most ``tolerance`` × the joint's range is kept
    as read and described in ``notes``; farther out it is an error.
    """
    q = np.empty(robot.n_joints)
    for k, (name, joint) in enumerate(zip(joint_columns(robot), robot.joints)):
        shown = _number(table, line, fields, name)
        q[k] = shown / joint.display_factor
        past = max(joint.lower - q[k], q[k] - joint.upper, 0.0)
        if past <= 1e-12:
            continue
        lo, hi = joint.lower * joint.display_factor, joint.upper * joint.display_factor
        where = (f"{shown:g} {joint.display_unit} is outside the limits of joint {joint.name} "
                 f"[{lo:g}, {hi:g}] {joint.display_unit}")
        span = joint.upper - joint.lower
        if not np.isfinite(span) or past > tolerance * span:
            hint = f" (more than {tolerance:.0%} of the range past it)" if tolerance else ""
            if joint.kind == "revolute" and joint.lower <= shown <= joint.upper:
                hint += (f"; read as radians ({np.degrees(shown):.4g} deg) it is inside: the "
                         f"file is likely in radians, and q must be in degrees")
            raise DataError(where + hint, table.path, line, table.col(name))
        notes.append(str(DataError(f"{where} by {past * joint.display_factor:.3g} "
                                   f"{joint.display_unit}: accepted as measured",
                                   table.path, line, table.col(name))))
    return q


#: Configurations a file needs before all-small angles are taken for radians.
RADIANS_MIN_CONFIGURATIONS = 3


def check_not_radians(q, robot, path) -> None:
    """Refuse joint values (SI, read from degrees) that are all within ±π·1.05 *degrees*
    while the revolute limits span far more: the file was written in radians.

    Raises
    ------
    DataError
        Naming radians as the likely cause, with the largest value and the span.
    """
    q = np.atleast_2d(np.asarray(q, float))
    revolute = [k for k, j in enumerate(robot.joints) if j.kind == "revolute"]
    if not revolute or len(q) < RADIANS_MIN_CONFIGURATIONS:
        return
    shown = np.degrees(np.abs(q[:, revolute]))
    span = np.degrees([robot.joints[k].upper - robot.joints[k].lower for k in revolute])
    largest = float(shown.max())
    if 0.0 < largest <= np.pi * 1.05 and np.max(np.minimum(span, 1e6)) > 20 * np.pi:
        raise DataError(f"every revolute joint value is within ±{largest:.3g} deg while the "
                        f"limits span up to {np.max(np.minimum(span, 1e6)):.0f} deg: the file "
                        f"is likely in radians; q must be in degrees (multiply by 180/π)", path)


def _parse_rows(table, robot, row_parser, skip_bad):
    """Apply ``row_parser`` to every row; drop and report bad rows if asked."""
    parsed, dropped = [], []
    for line, fields in table.rows:
        try:
            if len(fields) != len(table.columns):
                hint = ("; decimal commas? separate the fields with ';' to use them"
                        if len(fields) > len(table.columns) and not table.decimal_comma else "")
                raise DataError(f"{len(fields)} fields where the header has "
                                f"{len(table.columns)}{hint}", table.path, line)
            parsed.append((line, row_parser(line, fields)))
        except DataError as exc:
            if not skip_bad:
                raise
            dropped.append(str(exc))
    if not parsed:
        raise DataError("no valid data rows", table.path)
    return parsed, dropped


@gc_paused()
def read_measurements(path, robot, tool, sigma_mm: float | None = None, skip_bad: bool = False,
                      require_xyz: bool = True, session: str | None = None) -> Measurements:
    """Read a measurement CSV (formats.md §3).

    Parameters
    ----------
    path : path-like
    robot : Robot
        Gives N (columns q1..qN, deg or mm) and the joint limits.
    tool : Tool
        Gives the marker names.
    sigma_mm : float, optional
        σ (mm) of rows without a ``sigma`` value. With neither (no column, no
        σ), σ is unknown: a provisional :data:`PROVISIONAL_SIGMA_MM` is used and
        ``sigma_estimated`` is set, so identification estimates σ from the residuals.
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
        :data:`LIMIT_TOLERANCE` of the range is kept, with a message in
        ``warnings``.

    Raises
    ------
    DataError
        Naming file, line and column of a bad value; naming the file when x, y,
        z look like metres (their spread ~1/1000 of the one the nominal robot
        gives these joint values: :mod:`~doe_calib.io.reading_units`).
    """
    table = read_table(path)
    default_session = session or Path(str(path)).stem
    header_line = table.numbers[0] - 1
    qcols = joint_columns(robot)
    required = ["pose", *qcols, "marker", *(XYZ if require_xyz else ())]
    optional = [*WRENCH, "temperature", "sigma", "session", *approach_columns(robot),
                *(() if require_xyz else XYZ), *PREDICTED_STD]
    extra = _check_columns(table, required, optional, header_line)
    explicit = _checkapproach_columns(table, robot, header_line)
    estimated = "sigma" not in table.columns and sigma_mm is None
    sigma_mm = PROVISIONAL_SIGMA_MM if estimated else sigma_mm
    if sigma_mm is not None and not sigma_mm > 0:
        raise DataError(f"σ must be positive, got {sigma_mm} mm", table.path)
    first_q, seen, notes = {}, {}, []

    def row(line, fields):
        pose = fields[table.columns.index("pose")]
        marker = fields[table.columns.index("marker")]
        session = fields[table.columns.index("session")] if "session" in table.columns \
            else default_session
        if not pose:
            raise DataError("empty pose id", table.path, line, table.col("pose"))
        if not session:
            raise DataError("empty session name", table.path, line, table.col("session"))
        if marker not in tool.names:
            raise DataError(f"marker {marker!r} is not in the tool file (markers: "
                            f"{', '.join(tool.names)})", table.path, line, table.col("marker"))
        q = _joints(table, line, fields, robot, LIMIT_TOLERANCE, notes)
        shown = q * robot.display_factors
        if (session, pose) in first_q:
            ref_line, ref = first_q[session, pose]
            bad = np.flatnonzero(np.abs(shown - ref) > Q_TOL)
            if bad.size:
                raise DataError(f"pose {pose!r} has q{bad[0] + 1} = {shown[bad[0]]:g} here but "
                                f"{ref[bad[0]]:g} on line {ref_line}; all rows of a pose share q",
                                table.path, line, table.col(qcols[bad[0]]))
        wrench = np.array([_number(table, line, fields, c, 0.0) for c in WRENCH])
        temp = _number(table, line, fields, "temperature", np.nan)
        sigma = _number(table, line, fields, "sigma", sigma_mm)
        if sigma is None or not sigma > 0:
            raise DataError(f"σ must be positive, got {sigma}", table.path, line,
                            table.col("sigma"))
        xyz = np.array([_number(table, line, fields, c, np.nan if not require_xyz else None)
                        for c in XYZ]) / 1000.0
        approach = _approach(table, line, fields, robot) if explicit else None
        key = (pose, tuple(wrench), temp if np.isfinite(temp) else None, approach, session)
        if (key, marker) in seen:
            raise DataError(f"marker {marker!r} is read twice in pose {pose!r} under the same "
                            f"load (first on line {seen[key, marker]})", table.path, line,
                            table.col("marker"))
        seen[key, marker] = line
        first_q.setdefault((session, pose), (line, shown))
        return key, q, wrench, temp, tool.index(marker), xyz, sigma / 1000.0

    cols = None if skip_bad else read_columns(table, robot, tool, sigma_mm, require_xyz,
                                              explicit, default_session)
    dropped = []
    if cols is None:  # row by row, naming file, line and column of each problem
        parsed, dropped = _parse_rows(table, robot, row, skip_bad)
        first, index, config = {}, {}, []  # configuration key → (q, wrench, temperature)
        for _, (key, q, wrench, temp, *_) in parsed:
            first.setdefault(key, (q, wrench, temp))
            config.append(index.setdefault(key, len(index)))
        cols = Columns(list(first), np.array(config), np.array([v[0] for v in first.values()]),
                       np.array([v[1] for v in first.values()]),
                       np.array([v[2] for v in first.values()]),
                       np.array([p[4] for _, p in parsed]), np.array([p[5] for _, p in parsed]),
                       np.array([p[6] for _, p in parsed]),
                       np.array([line for line, _ in parsed]))
    check_not_radians(cols.q, robot, table.path)
    session = tuple(k[4] for k in cols.keys)
    if explicit:
        approach = np.array([k[3] for k in cols.keys])
    else:  # each session's own visiting order
        approach = np.zeros_like(cols.q)
        for name in dict.fromkeys(session):
            mine = np.array([s == name for s in session])
            approach[mine] = _derived_approach(cols.q[mine], robot)
    cfg = Configurations.from_arrays(cols.q, cols.wrench, cols.temperature[:, None],
                                     [k[0] for k in cols.keys], approach)
    meas = Measurements(cfg, cols.config, cols.marker, cols.xyz, cols.sigma, cols.line,
                        table.path, tuple(dropped),
                        ((_ignored_note(table, extra),) if extra else ()) + tuple(notes),
                        session, estimated,
                        reading_sigma_source("sigma" in table.columns, estimated))
    return _with_unit_check(meas, robot, tool)


def reading_sigma_source(has_column: bool, unknown: bool) -> str:
    """The σ source of a file's readings: its ``sigma`` column, else the σ given, else none
    (estimated; :mod:`doe_calib.estimation.sigma`)."""
    return PER_READING if has_column else ESTIMATED if unknown else GIVEN


def _with_unit_check(meas, robot, tool) -> Measurements:
    """``meas``, unless its x, y, z look like metres (:mod:`~doe_calib.io.reading_units`)."""
    from doe_calib.io.reading_units import metres_finding

    finding = metres_finding(meas.xyz, robot, meas.configurations.q, meas.config,
                             tool.position_array[meas.marker], meas.sessions[meas.config])
    if finding is not None:
        raise DataError(finding, meas.source)
    return meas


def read_design(path, robot) -> Configurations:
    """Read a design (formats.md §4): the CSV, or the JSON ``doe-calib design`` writes.

    CSV: pose, q1..qN (deg/mm), optional wrench, temperature, and optional
    ``approach1`` … ``approachN`` columns as in a measurement file; without
    them the directions come from the row order (module notes), as for the
    poses of a JSON design (where a pose plans no direction for a joint). A
    JSON design must be for ``robot``'s joints.
    """
    if Path(path).suffix.lower() == ".json":
        return _read_design_json(path, robot)
    table = read_table(path)
    header_line = table.rows[0][0] - 1
    extra = _check_columns(table, ["pose", *joint_columns(robot)],
                           [*WRENCH, "temperature", *approach_columns(robot)], header_line)
    if extra:  # the design's configurations have no place for notes
        warnings.warn(_ignored_note(table, extra), DataWarning, stacklevel=2)
    explicit = _checkapproach_columns(table, robot, header_line)

    def row(line, fields):
        pose = fields[table.columns.index("pose")]
        if not pose:
            raise DataError("empty pose id", table.path, line, table.col("pose"))
        return (pose, _joints(table, line, fields, robot),
                [_number(table, line, fields, c, 0.0) for c in WRENCH],
                _number(table, line, fields, "temperature", np.nan),
                _approach(table, line, fields, robot) if explicit else None)

    parsed, _ = _parse_rows(table, robot, row, False)
    rows = [p for _, p in parsed]
    q = np.array([r[1] for r in rows])
    check_not_radians(q, robot, table.path)
    approach = np.array([r[4] for r in rows]) if explicit else _derived_approach(q, robot)
    return Configurations.from_arrays(q, [r[2] for r in rows], [[r[3]] for r in rows],
                                      [r[0] for r in rows], approach)


def _read_design_json(path, robot) -> Configurations:
    """The configurations of a design JSON, checked against ``robot``'s joints and limits."""
    from doe_calib.design.result import DesignResult

    try:
        design = DesignResult.from_json(path)
    except (KeyError, TypeError, ValueError) as exc:
        raise DataError(f"not a complete doe_calib design file ({exc!r} is missing or "
                        f"malformed)", path) from None
    if design.robot.joint_names != robot.joint_names:
        raise DataError(f"the design is for joints {', '.join(design.robot.joint_names)}, the "
                        f"robot has {', '.join(robot.joint_names)}", path)
    cfg = design.configurations
    for c, q in enumerate(cfg.q):
        outside = np.flatnonzero((q < robot.lower - 1e-12) | (q > robot.upper + 1e-12))
        if outside.size:
            joint = robot.joints[outside[0]]
            raise DataError(f"pose {cfg.pose[c]!r}: q{outside[0] + 1} = "
                            f"{q[outside[0]] * joint.display_factor:g} {joint.display_unit} is "
                            f"outside the limits of joint {joint.name}", path)
    approach = np.where(cfg.approach != 0, cfg.approach, _derived_approach(cfg.q, robot))
    return Configurations.from_arrays(cfg.q, cfg.wrench, pose=cfg.pose, approach=approach)


def _configuration_fields(cfg, c, robot) -> list[str]:
    q = cfg.q[c] * robot.display_factors
    return [cfg.pose[c], *map(repr, map(float, q)), *map(repr, map(float, cfg.wrench[c]))]


def _write(path, comment, header, rows):
    buf = _io.StringIO()
    buf.write(f"# {comment}\n")
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(header)
    writer.writerows(rows)
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
        not np.array_equal(approach, _derived_approach(cfg.q[order], robot))


def _approach_fields(cfg, c) -> list[str]:
    return [str(int(a)) for a in cfg.approach[c]]


def write_measurements(path, measurements, robot, tool, std=None) -> None:
    """Write readings as a measurement CSV (deg/mm, mm, N, N·m), exactly re-readable.

    The approach columns are written only when reading back would not derive
    the same directions from the order of the rows (module notes); the
    ``session`` column only when the readings come from several sessions.
    ``std`` (K, 3), m: a prediction's standard deviation of each coordinate,
    written as the :data:`PREDICTED_STD` columns in mm (ignored on reading).
    """
    cfg = measurements.configurations
    with_temp = bool(np.isfinite(cfg.temperature).any())
    order = np.unique(measurements.config, return_index=True)
    order = order[0][np.argsort(order[1])]  # configurations in order of first appearance
    with_approach = _approach_needed(cfg, order, robot)
    sessions = measurements.sessions
    with_session = len(set(sessions)) > 1
    header = ["pose", *joint_columns(robot), *WRENCH, "marker", *XYZ,
              *(["temperature"] if with_temp else []), "sigma",
              *(approach_columns(robot) if with_approach else []),
              *(["session"] if with_session else []), *(PREDICTED_STD if std is not None else [])]
    std_mm = None if std is None else np.asarray(std, float) * 1000.0
    rows = []
    for c, j, xyz, s in zip(measurements.config, measurements.marker, measurements.xyz,
                            measurements.sigma):
        temp = [repr(float(cfg.env[c, 0])) if np.isfinite(cfg.env[c, 0]) else ""]
        rows.append([*_configuration_fields(cfg, c, robot), tool.names[j],
                     *map(repr, map(float, xyz * 1000.0)), *(temp if with_temp else []),
                     repr(float(s * 1000.0)),
                     *(_approach_fields(cfg, c) if with_approach else []),
                     *([sessions[c]] if with_session else []),
                     *(map(repr, map(float, std_mm[len(rows)])) if std is not None else [])])
    _write(path, "doe_calib measurements: q in deg (mm for prismatic joints), x/y/z and sigma "
                 "in mm, forces in N, moments in N·m, temperature in °C", header, rows)


def write_design(path, configurations, robot) -> None:
    """Write configurations as a design CSV (formats.md §4).

    The approach columns are written only when some direction is planned (not
    0) and reading back would not derive the same from the row order.
    """
    cfg = configurations
    with_temp = bool(np.isfinite(cfg.temperature).any())
    with_approach = bool(np.any(cfg.approach != 0)) and \
        _approach_needed(cfg, np.arange(len(cfg)), robot)
    header = ["pose", *joint_columns(robot), *WRENCH, *(["temperature"] if with_temp else []),
              *(approach_columns(robot) if with_approach else [])]
    rows = []
    for c in range(len(cfg)):
        t = cfg.env[c, 0]
        rows.append(_configuration_fields(cfg, c, robot)
                    + ([repr(float(t)) if np.isfinite(t) else ""] if with_temp else [])
                    + (_approach_fields(cfg, c) if with_approach else []))
    _write(path, "doe_calib design: q in deg (mm for prismatic joints), forces in N, moments "
                 "in N·m", header, rows)


def row_number(table, line, fields, name, default=None) -> float:
    """The number in column ``name`` of one row (file units), or ``default`` when absent.

    For other readers of our CSV files (formats.md): a bad value raises a
    :class:`~doe_calib.errors.DataError` naming file, line and column.
    """
    return _number(table, line, fields, name, default)


def row_joints(table, line, fields, robot, notes: list) -> np.ndarray:
    """q of one row in SI, checked against the limits as a measurement file's are.

    A value a hair past a limit (:data:`LIMIT_TOLERANCE`) is kept and described in ``notes``.
    """
    return _joints(table, line, fields, robot, LIMIT_TOLERANCE, notes)


def parse_rows(table, robot, row_parser) -> list:
    """``[(line, row_parser(line, fields)), …]`` for every row; a row of the wrong width raises."""
    return _parse_rows(table, robot, row_parser, False)[0]
