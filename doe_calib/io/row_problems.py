"""The bad rows of a table, found a check at a time over every row.

Each check marks the rows it refuses (a boolean per row) and says, for any one
of them, what is wrong and in which column. Checks carry a rank: the order in
which a reader going along one row would make them. The problem reported is
the one such a reader meets first: in the first bad row, the check of lowest
rank; with ``skip_bad`` every bad row is dropped and told by its first problem.

>>> import numpy as np
>>> from doe_calib.io.table import Table
>>> t = Table("f.csv", ["pose", "x"], 1, [2, 3, 4], ["a,1", "b,z", ",q"])
>>> p = RowProblems(t)
>>> p.check(1, np.array([False, False, True]), lambda i: "empty pose id", "pose")
>>> p.check(2, np.array([False, True, True]), lambda i: "not a number", "x")
>>> p.raise_first()
Traceback (most recent call last):
doe_calib.errors.DataError: f.csv, line 3, column 'x' (2): not a number
"""
from __future__ import annotations

import numpy as np

from doe_calib.errors import DataError


class RowProblems:
    """The checks made on the rows of ``table`` and the rows each refused."""

    def __init__(self, table):
        self.table = table
        self.checks = []  # (rank, bad rows, message(row), column name or None)

    def check(self, rank, bad, message, column: str | None = None) -> None:
        """Record a check of ``rank`` (a number, or a tuple ordering checks within one)
        that refuses the rows ``bad`` (R,) (bool); ``message(i)`` says what is wrong
        with row i."""
        bad = np.asarray(bad, bool)
        if bad.any():
            self.checks.append((_ranked(rank), bad, message, column))

    def failing(self, below=None) -> np.ndarray:
        """Rows refused by any check (of rank below ``below`` when given), shape (R,)."""
        out = np.zeros(len(self.table.numbers), bool)
        for rank, bad, _, _ in self.checks:
            if below is None or rank < _ranked(below):
                out |= bad
        return out

    def error(self, i: int) -> DataError:
        """The first problem of row ``i`` (which some check refused)."""
        _, _, message, column = min((c for c in self.checks if c[1][i]), key=lambda c: c[0])
        return DataError(message(i), self.table.path, self.table.numbers[i],
                         None if column is None else self.table.col(column))

    def raise_first(self) -> None:
        """Raise the problem a reader going row by row meets first, if any."""
        bad = np.flatnonzero(self.failing())
        if bad.size:
            raise self.error(int(bad[0]))

    def dropped(self) -> tuple:
        """One message per refused row, in file order."""
        return tuple(str(self.error(int(i))) for i in np.flatnonzero(self.failing()))


def _ranked(rank) -> tuple:
    """A rank as a tuple: ``5`` comes after ``(4, 2)`` and before ``(5, 0)``."""
    return rank if isinstance(rank, tuple) else (rank,)


def earlier_in_group(group, eligible) -> np.ndarray:
    """For each row, the first ``eligible`` row of its ``group`` when that row comes before
    it, else -1.

    Parameters
    ----------
    group : ndarray of int, shape (R,)
        Rows with one number belong together (a pose, a reading).
    eligible : ndarray of bool, shape (R,)
        Rows that may stand first in their group (those a reader would have kept).

    Examples
    --------
    >>> earlier_in_group(np.array([0, 1, 0, 0]), np.array([False, True, True, True])).tolist()
    [-1, -1, -1, 2]
    """
    first = np.full(int(group.max(initial=-1)) + 1, len(group))
    rows = np.flatnonzero(eligible)
    np.minimum.at(first, group[rows], rows)
    anchor = first[group]
    return np.where(anchor < np.arange(len(group)), anchor, -1)
