"""A clean measurement table read a column at a time (the fast path of ``read_measurements``).

Parsing 100 000 rows one cell at a time in Python takes tens of seconds.
Here each column is converted and checked as one numpy array: from the
file's text in one ``numpy.loadtxt`` pass when the table is clean (no
quotes, no white space, no empty number), else from the split fields; the
configurations are keyed by integer codes (``numpy.unique``). This path
never reports: on the first thing it does not accept (a bad number, an
empty cell without a default, a value past a joint limit, an unknown marker,
a repeated reading, rows of one pose disagreeing on q) it returns None, and
the caller reads the file row by row, the reader that names the file, line
and column of every problem.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from doe_calib.io.columns import PLAUSIBLE, Q_TOL, WRENCH, XYZ, approach_columns, joint_columns


@dataclass(frozen=True)
class Columns:
    """The rows of a measurement table as arrays (SI), in file order.

    ``keys`` are the configuration keys ``(pose, wrench, temperature or None,
    approach or None, session)`` in order of first appearance; ``config``
    indexes them per row; ``q``, ``wrench``, ``temperature`` are per key.
    """

    keys: list
    config: np.ndarray
    q: np.ndarray
    wrench: np.ndarray
    temperature: np.ndarray
    marker: np.ndarray
    xyz: np.ndarray
    sigma: np.ndarray
    line: np.ndarray


def _strings(table, names) -> dict:
    """The columns ``names`` of a clean table (:attr:`~doe_calib.io.table.Table.clean`) as
    lists of str, in one C pass over its text."""
    if not names:
        return {}
    at = [table.columns.index(n) for n in names]
    out = np.loadtxt(table.text, delimiter=table.separator, usecols=at, comments=None,
                     ndmin=2, dtype=str, encoding=None)
    return {n: out[:, k].tolist() for k, n in enumerate(names)}


def _converted(table, names) -> dict | None:
    """The columns ``names`` of a clean table (:attr:`~doe_calib.io.table.Table.clean`) as
    floats in one C pass over its text (``numpy.loadtxt``); None when any cell is not a
    plain number (an empty cell, a decimal comma, ``1_000``, ...: then each column is
    converted alone, from the split fields).

    ``loadtxt`` accepts a subset of what ``float`` accepts (no ``1_000``, no non-ASCII
    digits), with the same correctly rounded values.
    """
    if table.decimal_comma or not names:
        return None
    at = [table.columns.index(n) for n in names]
    try:
        out = np.loadtxt(table.text, delimiter=table.separator, usecols=at, comments=None, ndmin=2,
                         dtype=float, encoding=None)
    except ValueError:
        return None
    if out.shape != (len(table.text), len(names)):
        return None
    return {n: out[:, k] for k, n in enumerate(names)}


def _numbers(table, fields, name, default=None, converted=None):
    """Column ``name`` as floats (``default`` for empty cells); None if a cell is not a finite
    number or is outside the column's plausible range. ``converted``: the columns
    :func:`_converted` gave, when it could."""

    if converted is not None:
        out = converted[name]
        if not np.isfinite(out).all():
            return None
    else:
        i = table.columns.index(name)
        raw = [f[i] for f in fields]
        text = raw if default is None else [t if t else default for t in raw]
        try:
            out = np.array(text, dtype=float) if not table.decimal_comma else \
                np.array([t.replace(",", ".") for t in text], dtype=float)
        except ValueError:
            return None
        finite = np.isfinite(out)
        if not finite.all() and not np.all(finite | np.array([t == "" for t in raw], bool)):
            return None
    if name in PLAUSIBLE:
        low, high, _ = PLAUSIBLE[name]
        if np.any((out < low) | (out > high)):
            return None
    return out


def read_columns(table, robot, tool, sigma_mm, require_xyz: bool, explicit: bool,
                 default_session: str) -> Columns | None:
    """The table's rows as :class:`Columns`, or None when any row needs the row-by-row reader.

    Parameters as in :func:`~doe_calib.io.csv_files.read_measurements`; ``table`` is its
    parsed CSV, ``explicit``: the file has approach columns.
    """

    n_cols = len(table.columns)
    col = {c: i for i, c in enumerate(table.columns)}
    named = [c for c in ("pose", "marker", "session") if c in col]
    clean = table.clean  # each field is the text between separators: no split needed
    if clean:
        if any(line.count(table.separator) != n_cols - 1 for line in table.text):
            return None
        fields = None
        strings = _strings(table, named)
    else:
        fields = [f for _, f in table.rows]
        if any(len(f) != n_cols for f in fields):
            return None
        strings = {c: [f[col[c]] for f in fields] for c in named}
    pose, marker_names = strings["pose"], strings["marker"]
    session = strings["session"] if "session" in col else [default_session] * len(pose)
    if not all(pose) or not all(session) or not set(marker_names) <= set(tool.names):
        return None
    numeric = [*joint_columns(robot), *WRENCH, "temperature", "sigma", *XYZ,
               *(approach_columns(robot) if explicit else ())]
    conv = _converted(table, [c for c in numeric if c in col]) if clean else None
    if conv is None and fields is None:
        fields = [f for _, f in table.rows]
    shown = [_numbers(table, fields, c, None, conv) for c in joint_columns(robot)]
    wrench = [_numbers(table, fields, c, "0", conv) if c in col else np.zeros(len(pose))
              for c in WRENCH]
    temp = _numbers(table, fields, "temperature", "nan", conv) if "temperature" in col else \
        np.full(len(pose), np.nan)
    if "sigma" in col:
        sigma = _numbers(table, fields, "sigma", None if sigma_mm is None else repr(sigma_mm),
                         conv)
    else:
        sigma = np.full(len(pose), sigma_mm)
    xyz = [_numbers(table, fields, c, None if require_xyz else "nan", conv) if c in col
           else np.full(len(pose), np.nan) for c in XYZ]
    approach = [_numbers(table, fields, c, None, conv) for c in approach_columns(robot)] \
        if explicit else []
    arrays = shown + wrench + [temp, sigma] + xyz + approach
    if any(a is None for a in arrays):
        return None
    shown, wrench, xyz = np.column_stack(shown), np.column_stack(wrench), np.column_stack(xyz)
    if not np.all(sigma > 0):
        return None
    q = shown / robot.display_factors
    lower = np.array([j.lower for j in robot.joints])
    upper = np.array([j.upper for j in robot.joints])
    if np.any(q < lower - 1e-12) or np.any(q > upper + 1e-12):
        return None
    if explicit:
        approach = np.column_stack(approach)
        if not np.all(np.isin(approach, (-1.0, 0.0, 1.0))):
            return None
        approach = approach + 0.0  # no -0.0
    # rows of one (session, pose) share q
    pose_code, session_code = _codes(pose), _codes(session)
    _, first, same_pose = np.unique(_combined([session_code, pose_code]), return_index=True,
                                    return_inverse=True)
    if np.any(np.abs(shown - shown[first[same_pose]]) > Q_TOL):
        return None
    # a configuration is (pose, wrench, temperature, approach, session), by value
    parts = [pose_code, *(_codes(w + 0.0) for w in wrench.T),
             _codes(np.where(np.isfinite(temp), temp + 0.0, np.inf)),
             *(_codes(a) for a in (approach.T if explicit else ())), session_code]
    _, first, config = np.unique(_combined(parts), return_index=True, return_inverse=True)
    order = np.argsort(first)  # configurations in order of first appearance
    rank = np.empty(len(order), int)
    rank[order] = np.arange(len(order))
    config, first_row = rank[config].reshape(-1), first[order]
    rows = first_row.tolist()
    keys = [(pose[k], tuple(w), t if math.isfinite(t) else None,
             tuple(a) if explicit else None, session[k])
            for k, w, t, a in zip(rows, wrench[first_row].tolist(), temp[first_row].tolist(),
                                  approach[first_row].tolist() if explicit else rows)]
    index = {}
    for i, name in enumerate(tool.names):
        index.setdefault(name, i)
    marker = np.array([index[m] for m in marker_names], int)
    pair = config * tool.n_markers + marker
    if len(np.unique(pair)) != len(pair):  # a marker read twice in one configuration
        return None
    return Columns(keys, config, q[first_row], wrench[first_row], temp[first_row], marker,
                   xyz / 1000.0, sigma / 1000.0, np.array(table.numbers))


def _codes(values) -> np.ndarray:
    """An integer per row, equal where the values are equal (strings or floats, not NaN)."""
    if isinstance(values, np.ndarray):
        return np.unique(values, return_inverse=True)[1].reshape(-1)
    seen = {}
    return np.array([seen.setdefault(v, len(seen)) for v in values], np.int64)


def _combined(codes) -> np.ndarray:
    """One integer per row, equal where every one of ``codes`` is equal (below rows²)."""
    out = codes[0]
    for c in codes[1:]:
        out = np.unique(out * (int(c.max(initial=0)) + 1) + c, return_inverse=True)[1]
    return out.reshape(-1)
