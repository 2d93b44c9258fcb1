"""A CSV file as a table of text columns, converted a whole column at a time.

UTF-8 (a bad byte is reported with its line and column); fields separated by
commas, or by semicolons or tabs as the header shows, and then a number may
have a decimal comma. Shared by every reader of our CSV files.

Columns are read whole: the numbers of a clean table (no quote, white space
or NUL anywhere, every row as wide as the header) in one ``numpy.loadtxt``
pass over its text; any other table, or a column ``loadtxt`` refuses (an
empty cell, ``1_000``), from its split fields with ``float``. Both give the
same correctly rounded values; the ``loadtxt`` pass is what makes a large file
quick (the 100 002-reading CSV of benchmarks section (f): 0.6–1.3 s read
whole, 3.7–4.0 s from split fields, 2 loaded cores). A cell that is not a number is marked, not
raised: the readers report the first bad cell of the file
(:mod:`~doe_calib.io.row_problems`).
"""
from __future__ import annotations

import csv
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from doe_calib.errors import DataError

#: Field separators a header may use.
DELIMITERS = (",", ";", "\t")
#: What ``str.strip`` removes (the same characters): a line without any needs no stripping.
_SPACE = re.compile(r"\s")
#: A quote, white space or NUL (which numpy's text arrays drop) in rows joined by newlines
#: (no row holds one): not clean. The same, for ASCII text, as single characters.
_NOT_CLEAN = re.compile(r'[^\S\n]|["\x00]')
_ASCII_NOT_CLEAN = ('"', "\x00", " ", "\t", "\r", "\x0b", "\x0c", "\x1c", "\x1d", "\x1e", "\x1f")


@dataclass(frozen=True)
class Numbers:
    """One column converted to floats.

    ``values`` (file units) is NaN where a cell is empty or not a number;
    ``empty`` marks the empty cells, ``bad`` the cells that are not a number.
    """

    values: np.ndarray
    empty: np.ndarray
    bad: np.ndarray


@dataclass
class Table:
    """Header and rows of a CSV file, each row with its physical line number.

    ``decimal_comma``: the fields are separated by ``;`` or tabs, so a number
    may be written with a decimal comma (``1,5``), as spreadsheets in many
    European locales write it. ``text`` holds each data row's line as read and
    ``numbers`` its line number; ``rows`` splits them into fields on first use
    (a clean table's columns are read from ``text`` without it).
    """

    path: str
    columns: list
    header_line: int
    numbers: list
    text: list
    decimal_comma: bool = False
    separator: str = ","
    split: list | None = field(default=None, repr=False)
    cache: dict = field(default_factory=dict, repr=False)  # what was read from the text

    @property
    def rows(self) -> list:
        """``(line, fields)`` of every data row, each field stripped of white space.

        Raises
        ------
        DataError
            A line that cannot be split into fields.
        """
        if self.split is None:
            self.split = split_rows(self.path, self.numbers, self.text, self.separator)
        return self.split

    @property
    def clean(self) -> bool:
        """No quote, white space or NUL in any data row: each field is the text between
        separators (what a whole-column reader of ``text`` may assume)."""
        if "clean" not in self.cache:
            joined = "\n".join(self.text)
            if joined.isascii():  # a few fast scans for the only characters that can spoil it
                self.cache["clean"] = not any(c in joined for c in _ASCII_NOT_CLEAN)
            else:
                self.cache["clean"] = not _NOT_CLEAN.search(joined)
        return self.cache["clean"]

    def col(self, name: str) -> str:
        return f"'{name}' ({self.columns.index(name) + 1})"

    def widths(self) -> np.ndarray:
        """Fields of each data row, shape (R,)."""
        if "widths" not in self.cache:
            self.cache["widths"] = \
                np.array([line.count(self.separator) for line in self.text]) + 1 \
                if self.split is None and self.clean else np.array([len(f) for _, f in self.rows])
        return self.cache["widths"]

    def _plain(self) -> bool:
        """Whether ``numpy.loadtxt`` may read the text: clean, every row as wide as the header."""
        return self.split is None and self.clean and \
            bool(np.all(self.widths() == len(self.columns)))

    def cells(self, names) -> dict:
        """Column name → the text of its cells (list of str, one per row; "" past a short row),
        for the columns present."""
        names = [n for n in names if n in self.columns]
        todo = [n for n in names if ("cells", n) not in self.cache]
        at = [self.columns.index(n) for n in todo]
        if at and self._plain():
            out = np.loadtxt(self.text, delimiter=self.separator, usecols=at, comments=None,
                             ndmin=2, dtype=str, encoding=None)
            self.cache.update({("cells", n): out[:, k].tolist() for k, n in enumerate(todo)})
        elif at:
            self.cache.update({("cells", n): [f[i] if i < len(f) else "" for _, f in self.rows]
                               for n, i in zip(todo, at)})
        return {n: self.cache["cells", n] for n in names}

    def floats(self, names) -> dict:
        """Column name → its cells as :class:`Numbers` (file units), for the columns present.

        The first call should name every numeric column a reader wants: a clean table
        converts them in one pass.
        """
        names = [n for n in names if n in self.columns]
        todo = [n for n in names if ("floats", n) not in self.cache]
        out = None
        if todo and self._plain() and not self.decimal_comma:
            try:
                out = np.loadtxt(self.text, delimiter=self.separator, comments=None, ndmin=2,
                                 usecols=[self.columns.index(n) for n in todo], dtype=float,
                                 encoding=None)
            except ValueError:
                out = None  # a cell loadtxt refuses: each column converted from its cells
        if out is not None and out.shape == (len(self.text), len(todo)):
            none = np.zeros(len(self.text), bool)
            self.cache.update({("floats", n): Numbers(out[:, k], none, none)
                               for k, n in enumerate(todo)})
        elif todo:
            self.cache.update({("floats", n): _converted(texts, self.decimal_comma)
                               for n, texts in self.cells(todo).items()})
        return {n: self.cache["floats", n] for n in names}


def _converted(texts: list, decimal_comma: bool) -> Numbers:
    """Cells as floats (``float``'s reading of each), empty and bad cells marked."""
    if decimal_comma:
        texts = [t.replace(",", ".") for t in texts]
    try:
        values = np.array(texts, dtype=float)
        bad = np.zeros(len(texts), bool)
    except ValueError:  # an empty or bad cell: one at a time
        values, bad = np.full(len(texts), np.nan), np.zeros(len(texts), bool)
        for i, t in enumerate(texts):
            try:
                values[i] = float(t)
            except ValueError:
                bad[i] = t != ""
    empty = np.array([t == "" for t in texts], bool)
    return Numbers(values, empty, bad)


def decode(path: str, data: bytes) -> str:
    """UTF-8 text of a file; a bad byte is reported with its line and column."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        start = data.rfind(b"\n", 0, exc.start) + 1
        column = len(data[start:exc.start].decode("utf-8-sig", errors="replace")) + 1
        raise DataError(f"byte 0x{data[exc.start]:02x} is not UTF-8 text: save the file as "
                        f"UTF-8 (it may be Latin-1 or Windows-1252)", path,
                        data.count(b"\n", 0, exc.start) + 1, column) from None


def delimiter(header: str) -> str:
    """The field separator of a file: the most frequent of , ; and tab in its header."""
    counts = {d: header.count(d) for d in DELIMITERS}
    best = max(counts, key=counts.get)
    return best if counts[best] > counts[","] else ","


def read_table(path) -> Table:
    """Header and rows of a CSV file separated by commas, semicolons or tabs.

    Raises
    ------
    DataError
        An unreadable or non-UTF-8 file, no header, a bad header, no rows.
    """
    path = str(path)
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise DataError(f"cannot read the file: {exc.strerror}", path) from exc
    text = decode(path, data)
    kept = [(number, line) for number, line in enumerate(text.splitlines(), start=1)
            if line.strip() and not line.lstrip().startswith("#")]
    if not kept:
        raise DataError("the file is empty: expected a header row", path, 1)
    sep = delimiter(kept[0][1])
    numbers, lines = [n for n, _ in kept[1:]], [t for _, t in kept[1:]]
    # One physical line is one record. With quotes each line gets its own reader (so an
    # open quote cannot swallow the next line), split now; without, on first use.
    (line, columns), = split_rows(path, [kept[0][0]], [kept[0][1]], sep)
    split = split_rows(path, numbers, lines, sep) if '"' in text else None
    for i, c in enumerate(columns):
        if not c:
            raise DataError("empty column name in the header", path, line, i + 1)
        if columns.index(c) != i:
            raise DataError(f"column {c!r} appears twice in the header", path, line, i + 1)
    if not lines:
        raise DataError("the file has a header but no data rows", path, line)
    return Table(path, columns, line, numbers, lines, sep != ",", sep, split)


def split_rows(path, numbers, lines, sep) -> list:
    """``(line number, fields)`` of each line split at ``sep``, fields stripped of white space.

    Raises
    ------
    DataError
        A line that cannot be split (naming it).
    """
    try:
        split = list(csv.reader(lines, delimiter=sep)) if not any('"' in t for t in lines) \
            else None
    except csv.Error:
        split = None  # the line at fault is found below
    rows = []
    for k, (number, line) in enumerate(zip(numbers, lines)):
        try:
            fields = split[k] if split is not None else next(csv.reader([line], delimiter=sep))
        except csv.Error as exc:
            raise DataError(f"cannot split the line into fields ({exc})", path, number) from None
        rows.append((number, [f.strip() for f in fields] if _SPACE.search(line) else fields))
    return rows
