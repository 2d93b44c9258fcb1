"""The columns a measurement, design and probe file share (formats.md §3, §4), their names
and plausible values, read and checked a column at a time.

Each function converts whole columns (:meth:`~doe_calib.io.table.Table.floats`)
and records what it refuses with a :class:`~doe_calib.io.row_problems.RowProblems`
under the rank it is given, so the reader reports the first bad value of the
file with its line and column (formats.md §3, §4).
"""
from __future__ import annotations

import re
from difflib import get_close_matches

import numpy as np

from doe_calib.errors import DataError
from doe_calib.io.measurements import approach_from_order

WRENCH = ("fx", "fy", "fz", "mx", "my", "mz")
XYZ = ("x", "y", "z")
Q_TOL = 1e-9  # file units: rows of one pose agree on q to this
#: Column → (lowest, highest, unit) of a plausible value; outside is a unit or typing error.
PLAUSIBLE = {"temperature": (-50.0, 150.0, "°C")}

#: Columns that look like doe_calib's own (a joint or approach column of another robot).
_OWN_PATTERN = re.compile(r"^(q|approach)\d+$")
#: difflib similarity above which an unknown column is taken for a typo of a known one.
TYPO_CUTOFF = 0.75
#: A measured joint value past a URDF limit by at most this fraction of the joint's range
#: is accepted with a note (an encoder at a hard stop, a rounded limit); farther is an error.
LIMIT_TOLERANCE = 0.02
#: Configurations a file needs before all-small angles are taken for radians.
RADIANS_MIN_CONFIGURATIONS = 3


def joint_columns(robot) -> list[str]:
    """Joint columns q1 … qN of a robot's measurement and design files (deg or mm)."""
    return [f"q{k + 1}" for k in range(robot.n_joints)]


def approach_columns(robot) -> list[str]:
    """Approach-direction columns approach1 … approachN (+1, −1 or 0)."""
    return [f"approach{k + 1}" for k in range(robot.n_joints)]


def check_columns(table, required, optional) -> tuple:
    """Refuse missing columns and typos of known ones; return the other extra columns.

    An unknown column is an error when it looks like a known one (a close
    match, e.g. ``sigam`` for ``sigma``, or a joint column the robot does not
    have); any other (``timestamp``) is ignored and returned for a note.
    """
    missing = [c for c in required if c not in table.columns]
    if missing:
        raise DataError(f"missing column(s) {', '.join(missing)}; the header must hold "
                        f"{', '.join(required)}", table.path, table.header_line, 1)
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
                            f"{', '.join(accepted)}", table.path, table.header_line,
                            f"'{c}' ({i + 1})")
        extra.append(c)
    return tuple(extra)


def ignored_note(table, extra) -> str:
    return (f"{table.path}: column(s) {', '.join(repr(c) for c in extra)} ignored (not "
            "doe_calib columns; docs/formats.md §3 lists them)")


def approach_given(table, robot) -> bool:
    """Whether the file gives the approach directions (all N columns; some is an error)."""
    names = approach_columns(robot)
    present = [c for c in names if c in table.columns]
    if present and len(present) < len(names):
        missing = [c for c in names if c not in table.columns]
        raise DataError(f"approach column(s) {', '.join(missing)} missing: give all of "
                        f"{names[0]} … {names[-1]} or none (then they come from the "
                        f"measurement order)", table.path, table.header_line,
                        table.col(present[0]))
    return bool(present)


def check_width(table, problems, rank) -> None:
    """Refuse rows with more or fewer fields than the header."""
    n, widths = len(table.columns), table.widths()

    def message(i):
        hint = ("; decimal commas? separate the fields with ';' to use them"
                if widths[i] > n and not table.decimal_comma else "")
        return f"{widths[i]} fields where the header has {n}{hint}"
    problems.check(rank, widths != n, message)


def texts(table, problems, rank, name, what: str | None = None, default: str = "") -> list:
    """The cells of a text column (``default`` for every row when the column is absent);
    with ``what``, an empty cell is refused as an empty ``what``."""
    if name not in table.columns:
        return [default] * len(table.numbers)
    cells = table.cells([name])[name]
    if what:
        problems.check(rank, [not c for c in cells], lambda i: f"empty {what}", name)
    return cells


def numbers(table, problems, rank, names, default=None) -> np.ndarray:
    """Columns ``names`` as floats (file units), shape (R, len(names)); ``default`` for empty
    cells and absent columns (None: an empty cell is refused, the column is required).

    Column k is checked at rank ``(rank, 2k)`` (a number) and ``(rank, 2k + 1)`` (inside
    the :data:`PLAUSIBLE` range of its column).
    """
    got = table.floats(names)
    out = np.empty((len(table.numbers), len(names)))
    for k, name in enumerate(names):
        if name not in got:
            out[:, k] = np.nan if default is None else default
            continue
        col = got[name]
        missing = col.empty if default is None else np.zeros_like(col.empty)
        bad = col.bad | missing | (~col.empty & ~np.isfinite(col.values))

        def message(i, name=name, col=col):
            text = table.cells([name])[name][i]
            kind = "a number" if col.bad[i] or col.empty[i] else "a finite number"
            return f"{text!r} is not {kind}"
        problems.check((rank, 2 * k), bad, message, name)
        out[:, k] = np.where(col.empty, np.nan if default is None else default, col.values)
        if name in PLAUSIBLE:
            low, high, unit = PLAUSIBLE[name]
            v = out[:, k]

            def outside(i, v=v, name=name, low=low, high=high, unit=unit):
                return (f"{v[i]:g} {unit} is not a plausible {name}: expected {low:g} to "
                        f"{high:g} {unit}")
            problems.check((rank, 2 * k + 1), ~bad & ((v < low) | (v > high)), outside, name)
    return out


def joints(table, problems, rank, robot, tolerance: float = 0.0, notes=None) -> np.ndarray:
    """q of every row in SI (R, N), checked against the limits.

    A value past a limit by at most ``tolerance`` × the joint's range is kept
    as read and described in ``notes``, a list given to receive ``(row, message)``
    pairs (file order); farther out it is refused.
    """
    names = joint_columns(robot)
    shown = numbers(table, problems, rank, names)
    q = shown / robot.display_factors
    near = []
    for k, (name, joint) in enumerate(zip(names, robot.joints)):
        past = np.maximum(np.maximum(joint.lower - q[:, k], q[:, k] - joint.upper), 0.0)
        past = np.where(np.isfinite(past), past, 0.0)
        span = joint.upper - joint.lower
        limit = tolerance * span if np.isfinite(span) else 0.0
        lo, hi = joint.lower * joint.display_factor, joint.upper * joint.display_factor
        unit = joint.display_unit

        def where(i, k=k, joint=joint, lo=lo, hi=hi, unit=unit):
            return (f"{shown[i, k]:g} {unit} is outside the limits of joint {joint.name} "
                    f"[{lo:g}, {hi:g}] {unit}")

        def outside(i, k=k, joint=joint, where=where):
            hint = f" (more than {tolerance:.0%} of the range past it)" if tolerance else ""
            if joint.kind == "revolute" and joint.lower <= shown[i, k] <= joint.upper:
                hint += (f"; read as radians ({np.degrees(shown[i, k]):.4g} deg) it is inside: "
                         f"the file is likely in radians, and q must be in degrees")
            return where(i) + hint
        problems.check((rank, 2 * k, 2), (past > 1e-12) & (past > limit), outside, name)
        for i in np.flatnonzero((past > 1e-12) & (past <= limit)):
            near.append((i, k, str(DataError(f"{where(i)} by {past[i] * joint.display_factor:.3g}"
                                              f" {unit}: accepted as measured", table.path,
                                              table.numbers[i], table.col(name)))))
    if notes is not None:
        notes.extend((i, text) for i, _, text in sorted(near))
    return q


def approach(table, problems, rank, robot) -> np.ndarray:
    """Approach directions of every row (R, N): 1, -1 or 0."""
    names = approach_columns(robot)
    got = table.floats(names)
    out = np.zeros((len(table.numbers), len(names)))
    for k, name in enumerate(names):
        v = got[name].values
        bad = ~np.isin(v, (-1.0, 0.0, 1.0))

        def message(i, name=name):
            return (f"{table.cells([name])[name][i]!r} is not an approach direction: write 1 "
                    f"(joint moving up), -1 (moving down) or 0 (unknown)")
        problems.check((rank, k), bad, message, name)
        out[:, k] = np.where(bad, 0.0, v) + 0.0  # no -0.0
    return out


def derived_approach(q, robot, sessions=None) -> np.ndarray:
    """Approach directions from the visiting order of configurations q (M, N), SI: the
    order of the rows, each session's own when ``sessions`` (M,) names them."""
    shown = np.asarray(q) * robot.display_factors
    if sessions is None:
        return approach_from_order(shown, Q_TOL)
    out = np.zeros_like(shown)
    for name in dict.fromkeys(sessions):
        mine = np.array([s == name for s in sessions])
        out[mine] = approach_from_order(shown[mine], Q_TOL)
    return out


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


def codes(values) -> np.ndarray:
    """An integer per row, equal where the values are equal (strings or floats; NaN equal)."""
    if isinstance(values, np.ndarray):
        return np.unique(values, return_inverse=True)[1].reshape(-1)
    seen = {}
    return np.array([seen.setdefault(v, len(seen)) for v in values], np.int64)


def combined(parts) -> np.ndarray:
    """One integer per row, equal where every one of ``parts`` (integer codes) is equal."""
    out = parts[0]
    for c in parts[1:]:
        out = np.unique(out * (int(c.max(initial=0)) + 1) + c, return_inverse=True)[1]
    return np.asarray(out).reshape(-1)
