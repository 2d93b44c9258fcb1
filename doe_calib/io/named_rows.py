"""Small CSV files of named things and their numbers: a sockets file, a planes file.

One row per thing: its id in the ``key`` column, then numbers in file units. Read by the
one CSV reader (:func:`.table.read_table`: commas, semicolons or tabs, ``#`` comments),
every error naming the file, line and column.
"""
from __future__ import annotations

import numpy as np

from doe_calib.errors import DataError
from doe_calib.io.table import read_table


def read_named_rows(path, key: str, required, optional=(), form: str = "") -> tuple:
    """The ids and numbers of a CSV of named rows.

    Parameters
    ----------
    path : str or Path
    key : str
        The column of each row's id (unique, not empty).
    required : sequence of str
        Numeric columns every row gives (file units).
    optional : sequence of str
        Numeric columns that may be absent or empty (NaN there).
    form : str
        What the file is, for the messages (e.g. "the sockets file is a CSV socket,x,y,z").

    Returns
    -------
    names : tuple of str
    values : dict
        Column → ndarray (R,), file units, in the rows' order.
    lines : list of int
        Each row's line in the file.

    Raises
    ------
    DataError
        No header or rows, a column missing, an id empty or given twice, a value not a
        number (the file, line and column named).
    """
    table = read_table(path)
    for c in (key, *required):
        if c not in table.columns:
            raise DataError(f"no column {c!r}: {form}", path, table.header_line)
    names, values, lines = [], {c: [] for c in (*required, *optional)}, []
    for line, fields in table.rows:
        cells = dict(zip(table.columns, fields))
        name = cells.get(key, "")
        if not name:
            raise DataError(f"a row without its {key}", path, line, key)
        if name in names:
            raise DataError(f"{key} {name!r} given twice", path, line, key)
        for c in values:
            values[c].append(_number(cells.get(c, ""), c in required, path, line, c))
        names.append(name)
        lines.append(line)
    return tuple(names), {c: np.array(v, float) for c, v in values.items()}, lines


def _number(text: str, required: bool, path, line: int, column: str) -> float:
    """The cell's number; NaN for an empty optional cell."""
    if not text and not required:
        return np.nan
    try:
        value = float(text)
    except ValueError:
        value = np.nan
    if not np.isfinite(value):
        raise DataError(f"{text!r} is not a number", path, line, column)
    return value
