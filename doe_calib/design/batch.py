"""Evaluation over tens of thousands of poses in fixed-size chunks.

``Function.map`` costs about 25 µs per mapped copy to build, so mapping once
over 40 000 configurations takes seconds; chunks of one fixed size build the
map once and reuse it (the last chunk is padded). The maps are kept per
thread, a few at a time.
"""
from __future__ import annotations

import threading

import casadi as ca
import numpy as np

CHUNK = 2048
_MAPS_KEPT = 16
_LOCAL = threading.local()


def chunks(m: int, size: int = CHUNK):
    """(rows of the result, padded row indices of one chunk) covering range(m) in chunks.

    Every chunk has ``min(size, m)`` indices, the last one padded with index 0.
    """
    size = min(size, m)
    for start in range(0, m, size):
        index = np.arange(start, start + size)
        yield slice(start, min(start + size, m)), np.where(index < m, index, 0)


def map_poses(function: ca.Function, q: np.ndarray) -> list[np.ndarray]:
    """A Function of one pose, ``f(q) -> (y_1, …)``, at every row of q (M, N).

    Returns
    -------
    list of ndarray
        One per output, shape (M, rows, cols).
    """
    q = np.atleast_2d(q)
    m = len(q)
    shapes = [function.size_out(i) for i in range(function.n_out())]
    out = [np.empty((m, *s)) for s in shapes]
    maps = getattr(_LOCAL, "maps", None)
    if maps is None:
        maps = _LOCAL.maps = {}
    for rows, index in chunks(m):
        key = (id(function), len(index))
        if key not in maps or maps[key][0] is not function:  # the Function, not a reused id
            if len(maps) >= _MAPS_KEPT:
                maps.pop(next(iter(maps)))
            maps[key] = (function, function.map(len(index)))
        res = maps[key][1](q[index].T)
        res = res if isinstance(res, (list, tuple)) else [res]
        for o, r, (nr, nc) in zip(out, res, shapes):
            block = np.asarray(r).reshape(nr, len(index), nc).transpose(1, 0, 2)
            o[rows] = block[: rows.stop - rows.start]
    return out
