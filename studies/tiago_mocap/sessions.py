"""The sessions as the user brings them: one wide CSV per session → SI Measurements."""
from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from doe_calib import Configurations, DataError, Measurements

from .robot import COLUMNS, SIGMA_FLOOR_MM


@dataclass(frozen=True, eq=False)
class Session:
    """One recording session.

    Attributes
    ----------
    name : str
        From the file name, e.g. ``2021-11-30-1403``.
    measurements : Measurements
        4 readings per posture, SI.
    time : ndarray, shape (M,)
        Start of each posture's averaging window since the session's first, s.
    jitter_mm : ndarray, shape (M,)
        The file's ``marker_std_mm`` per posture.
    start : float
        Unix time of the first posture, s.
    """

    name: str
    measurements: Measurements
    time: np.ndarray
    jitter_mm: np.ndarray
    start: float


def read_session(csv_path, sigma_mm: float | None = None) -> Session:
    """Read one wide session file into a :class:`Session` (see :func:`load_session`)."""
    path = Path(csv_path)
    name = path.stem.removeprefix("qualisys_").removesuffix("_static_postures")
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.reader(fh))
    except OSError as exc:
        raise DataError(f"cannot read the file: {exc.strerror}", path) from exc
    if not rows:
        raise DataError("the file is empty: expected a header row", path, 1)
    header = [c.strip() for c in rows[0]]
    missing = [c for c in COLUMNS if c not in header]
    if missing:
        raise DataError(f"missing columns: {', '.join(missing)}", path, 1)
    col = [header.index(c) for c in COLUMNS]
    values, lines = [], []
    for line, row in enumerate(rows[1:], start=2):
        if not any(f.strip() for f in row):
            continue
        out = []
        for name_c, i in zip(COLUMNS, col):
            try:
                v = float(row[i])
            except (IndexError, ValueError):
                v = float("nan")
            if not np.isfinite(v):
                text = row[i] if i < len(row) else ""
                raise DataError(f"{text!r} is not a finite number", path, line, name_c)
            out.append(v)
        values.append(out)
        lines.append(line)
    if not values:
        raise DataError("no posture rows after the header", path, 2)
    a = np.array(values)
    m = len(a)
    xyz = a[:, :12].reshape(m, 4, 3)
    q = a[:, 12:20]
    t, jitter = a[:, 20], a[:, 21]
    sig = np.full(m, sigma_mm) if sigma_mm is not None else np.maximum(jitter, SIGMA_FLOOR_MM)
    cfg = Configurations.from_arrays(q, pose=[f"{name}:{r + 1}" for r in range(m)])
    meas = Measurements(cfg, np.repeat(np.arange(m), 4), np.tile(np.arange(4), m),
                        xyz.reshape(-1, 3), np.repeat(sig, 4) / 1000.0,
                        np.repeat(np.array(lines), 4), str(path))
    return Session(name, meas, t - t[0], jitter, float(t[0]))


def load_session(csv_path, sigma_mm: float | None = None) -> Measurements:
    """Marker readings (SI) of one session file.

    Parameters
    ----------
    csv_path : path-like
        Wide file: ``x1..z4`` (m), the 8 joints (m, rad), ``t_start_robot`` (s),
        ``marker_std_mm``; one row per static posture.
    sigma_mm : float, optional
        Constant σ per coordinate (mm); default per row ``max(marker_std_mm,
        0.1 mm)``: the file's jitter, floored so that a quiet window does not
        get an outsized weight.

    Returns
    -------
    Measurements
        4 readings per posture (markers ``P1..P4`` in that order), pose ids
        ``<session>:<row>`` with ``row`` the 1-based data row; ``line`` is the
        file line.

    Raises
    ------
    DataError
        A missing column or a value that is not a finite number (file, line, column).
    """
    return read_session(csv_path, sigma_mm).measurements

def read_sessions(data_dir, sigma_mm: float | None = None) -> list:
    """Every ``*_static_postures.csv`` of ``data_dir``, in order of recording."""
    files = sorted(Path(data_dir).glob("*_static_postures.csv"))
    if not files:
        raise DataError("no *_static_postures.csv files", data_dir)
    return sorted((read_session(f, sigma_mm) for f in files), key=lambda s: s.start)
