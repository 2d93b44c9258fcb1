"""Readings of one marker in one pose taken more than once, and readings present twice.

A pose read again (same pose id, joint positions and load, the same marker)
shows the tracker's noise directly: :mod:`~doe_calib.estimation.repeatability`
pools the spread of such repeats into a σ that holds no model error. A reading
whose x, y, z are identical to the last digit to another's is not a repeat
but a copy (a file or session given twice): a tracker never reads the same
point twice to a nanometre. A copy is fitted twice (its weight doubled) and
tells nothing of the noise; :func:`copies_words` names each one.
"""
from __future__ import annotations

from itertools import groupby

import numpy as np

#: Copies named one by one in :func:`copies_words` (the rest by line only).
NAMED_COPIES = 5


def repeat_groups(measurements) -> np.ndarray:
    """The group of each reading: same pose id, joint positions, load and marker.

    Parameters
    ----------
    measurements : Measurements

    Returns
    -------
    ndarray of int, shape (K,)
        Readings with the same number are readings of one marker in one pose
        (whether in one configuration or in several: another session, another
        temperature).
    """
    cfg = measurements.configurations
    same = {}
    pose = np.array([same.setdefault((cfg.pose[c], cfg.q[c].tobytes(), cfg.wrench[c].tobytes()),
                                     len(same)) for c in range(len(cfg))], dtype=np.int64)
    if not len(measurements):
        return np.zeros(0, dtype=np.int64)
    key = pose[measurements.config] * (int(measurements.marker.max()) + 1) + measurements.marker
    return np.unique(key, return_inverse=True)[1].ravel()


def identical_copies(measurements, groups=None) -> np.ndarray:
    """Readings that repeat an earlier reading of their group to the last digit.

    Parameters
    ----------
    measurements : Measurements
    groups : ndarray of int, shape (K,), optional
        :func:`repeat_groups` when already at hand.

    Returns
    -------
    ndarray of int, shape (C, 2)
        (first reading, its copy) index pairs, in reading order; a reading present
        three times gives two pairs with the same first reading.
    """
    groups = repeat_groups(measurements) if groups is None else groups
    if not len(groups):
        return np.zeros((0, 2), dtype=np.int64)
    rows = np.column_stack([groups.astype(float), measurements.xyz])
    _, first, inverse = np.unique(rows, axis=0, return_index=True, return_inverse=True)
    original = first[inverse.ravel()]
    copy = np.flatnonzero(original != np.arange(len(groups)))
    return np.column_stack([original[copy], copy]).astype(np.int64)


def line_ranges(lines) -> str:
    """``[2, 3, 4, 9]`` → ``"2–4, 9"``: line numbers, runs shortened, in the given order."""
    runs = [[n for _, n in run] for _, run in groupby(enumerate(lines), lambda p: p[1] - p[0])]
    return ", ".join(str(r[0]) if len(r) == 1 else f"{r[0]}–{r[-1]}" for r in runs)


def copies_words(measurements, marker_names, copies=None) -> str | None:
    """The readings present twice, named (file, lines, pose, marker, session), or None.

    Parameters
    ----------
    measurements : Measurements
    marker_names : sequence of str
        The tool's marker names, by marker index.
    copies : ndarray, shape (C, 2), optional
        :func:`identical_copies` when already at hand.

    Returns
    -------
    str or None
        One paragraph: how many, the first :data:`NAMED_COPIES` by pose and marker with
        both lines (and sessions, when several), every copy's line, and what it does to
        the fit.

    Examples
    --------
    >>> from doe_calib.io.measurements import Configurations, Measurements, concatenate
    >>> cfg = Configurations.from_arrays([[0.0, 0.0]])
    >>> one = Measurements(cfg, np.array([0]), np.array([0]), np.array([[1.0, 2.0, 3.0]]),
    ...                    np.array([2e-5]), np.array([7]), "f.csv")
    >>> copies_words(concatenate([one, one]), ["A"])[:62]
    'f.csv: 1 reading is present twice, identical to the last digit'
    """
    copies = identical_copies(measurements) if copies is None else copies
    if not len(copies):
        return None
    cfg, line = measurements.configurations, measurements.line
    sessions = measurements.sessions
    several = len(set(sessions)) > 1

    def where(i):
        return f"line {line[i]}" + (f", session {sessions[measurements.config[i]]}"
                                    if several else "")

    named = [f"pose {cfg.pose[measurements.config[b]]} marker "
             f"{marker_names[measurements.marker[b]]} ({where(a)} and {where(b)})"
             for a, b in copies[:NAMED_COPIES]]
    more = len(copies) - len(named)
    n = len(copies)
    return (f"{measurements.source}: {n} reading{'s are' if n > 1 else ' is'} present twice, "
            f"identical to the last digit (the same file or session given twice?): "
            + "; ".join(named) + (f"; and {more} more" if more else "")
            + (f" (lines {line_ranges(line[copies[:, 1]])} repeat lines "
               f"{line_ranges(line[copies[:, 0]])})" if n > 1 else "")
            + ". A copy is fitted twice (its weight doubled: the stated std are too small) and "
              "tells nothing of the noise (it is left out of σ from repeated readings); "
              "remove the copies.")
