"""Visiting order of poses for short joint travel: nearest neighbour, then 2-opt and or-opt.

The cost of a synchronous PTP move a → b is the time of the slowest axis,
``t(a, b) = max_j |q_j(b) − q_j(a)| / v_j``. The order is an open path, optionally from
a fixed start; a heuristic within a few per cent of the optimum on a few poses
(``tests/test_export_ordering.py``).
"""
from __future__ import annotations

import numpy as np

#: Nearest-neighbour paths improved by 2-opt and or-opt (the shortest ones).
TRIES = 8

#: Joint speed assumed when the URDF gives none: rad/s (revolute), m/s (prismatic).
DEFAULT_SPEED = {"revolute": 1.0, "prismatic": 0.5}


def axis_speeds(robot) -> np.ndarray:
    """Maximum speed of each joint, shape (N,), rad/s or m/s.

    The URDF's ``<limit velocity>``, or :data:`DEFAULT_SPEED` when it gives none.
    """
    return np.array([j.velocity if j.velocity > 0 else DEFAULT_SPEED[j.kind]
                     for j in robot.joints])


def move_times(a, b, speed) -> np.ndarray:
    """Time of the synchronous move between each row of ``a`` and each row of ``b``.

    Parameters
    ----------
    a : array_like, shape (A, N)
    b : array_like, shape (B, N)
        Joint values, rad (m for prismatic joints).
    speed : array_like, shape (N,)
        Joint speeds, rad/s (m/s).

    Returns
    -------
    ndarray, shape (A, B)
        ``max_j |b_j − a_j| / v_j``, s.

    Examples
    --------
    >>> move_times([[0.0, 0.0]], [[1.0, 3.0]], [1.0, 2.0]).tolist()
    [[1.5]]
    """
    a, b = np.atleast_2d(np.asarray(a, float)), np.atleast_2d(np.asarray(b, float))
    return (np.abs(b[None, :, :] - a[:, None, :]) / np.asarray(speed, float)).max(axis=2)


def path_time(times, order, start=None) -> float:
    """Length (s) of the open path visiting ``order`` with move ``times`` (M, M); ``start``
    (M,): the move time from the start to each pose (None: start at the first pose)."""
    order = list(order)
    total = float(sum(times[i, j] for i, j in zip(order[:-1], order[1:])))
    return total + (float(start[order[0]]) if start is not None and order else 0.0)


def _nearest_neighbour(times, first: int) -> list:
    seen = np.zeros(len(times), dtype=bool)
    path = [first]
    seen[first] = True
    while not seen.all():
        path.append(int(np.argmin(np.where(seen, np.inf, times[path[-1]]))))
        seen[path[-1]] = True
    return path


def _two_opt(times, path: list, start) -> list:
    """Reverse segments while that shortens the path (cost before the first: ``start``)."""
    m = len(path)

    def before(i):  # cost of the edge into position i, before and after reversing
        return (lambda node: start[node] if start is not None else 0.0) if i == 0 else \
            (lambda node: times[path[i - 1], node])

    improved = True
    while improved:
        improved = False
        for i in range(m - 1):
            into = before(i)
            for k in range(i + 1, m):
                old = into(path[i]) + (times[path[k], path[k + 1]] if k + 1 < m else 0.0)
                new = into(path[k]) + (times[path[i], path[k + 1]] if k + 1 < m else 0.0)
                if new < old - 1e-12:
                    path[i:k + 1] = path[i:k + 1][::-1]
                    improved = True
    return path


def _or_opt(times, path: list, start) -> bool:
    """Move one segment of 1–3 poses (either way round) elsewhere if that shortens the path."""
    def edge(a, b):  # None: before the first pose / after the last
        if b is None:
            return 0.0
        if a is None:
            return 0.0 if start is None else float(start[b])
        return float(times[a, b])

    m = len(path)
    for size in (1, 2, 3):
        for i in range(m - size + 1):
            segment, rest = path[i:i + size], path[:i] + path[i + size:]
            left = path[i - 1] if i > 0 else None
            right = path[i + size] if i + size < m else None
            gain = edge(left, segment[0]) + edge(segment[-1], right) - edge(left, right)
            for piece in (segment, segment[::-1]):
                for at in range(len(rest) + 1):
                    x = rest[at - 1] if at > 0 else None
                    y = rest[at] if at < len(rest) else None
                    if edge(x, piece[0]) + edge(piece[-1], y) - edge(x, y) < gain - 1e-12:
                        path[:] = rest[:at] + piece + rest[at:]
                        return True
    return False


def short_path(times, start=None) -> np.ndarray:
    """A short open path through every pose (module notes): of the nearest-neighbour paths
    from every first pose, the :data:`TRIES` shortest improved by 2-opt and or-opt.

    ``times`` (M, M): symmetric move times, s; ``start`` (M,): the move time from the
    start to each pose (None: start anywhere). Returns the visiting order, (M,).

    Examples
    --------
    >>> q = [[0.0], [3.0], [1.0], [2.0]]
    >>> short_path(move_times(q, q, [1.0])).tolist()
    [0, 2, 3, 1]
    """
    times = np.asarray(times, float)
    m = len(times)
    if m == 0:
        return np.zeros(0, dtype=int)
    paths = sorted((_nearest_neighbour(times, f) for f in range(m)),
                   key=lambda p: path_time(times, p, start))
    paths = [_two_opt(times, p, start) for p in paths[:TRIES]]
    for p in paths:  # or-opt then 2-opt until neither shortens the path
        while _or_opt(times, p, start):
            _two_opt(times, p, start)
    return np.array(min(paths, key=lambda p: path_time(times, p, start)), dtype=int)
