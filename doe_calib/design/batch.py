"""Evaluation over tens of thousands of poses in fixed-size chunks.

Buffers for every one of 40 000 configurations would hold gigabytes; chunks
of one fixed size build one map and its buffers and reuse them (the last
chunk is padded). The chunks are small: building a map takes time in
proportion to its poses (70 ms for 2048 poses of the KR 270's blocks), while
evaluating 256 poses at a time costs no more per pose. Each map is evaluated
through CasADi's buffers straight into numpy arrays (no DM conversion). The
maps are kept per thread, a few at a time.
"""
from __future__ import annotations

import threading

import casadi as ca
import numpy as np

CHUNK = 256
_MAPS_KEPT = 16
_LOCAL = threading.local()


class _Mapped:
    """A Function of one pose mapped over ``m`` poses, with numpy buffers it reads and writes.

    CasADi's buffer interface evaluates straight from and into the numpy
    arrays: no DM is made, which for a large output costs several times the
    evaluation itself.
    """

    def __init__(self, function: ca.Function, m: int):
        self.function = function
        # the plain map: the named one with reduce lists is an MX wrapper built in time ∝ m
        self.mapped = function.map(m, "serial") if m > 1 else function
        self.arg = np.zeros(self.mapped.size_in(0)[::-1])
        self.res = [np.zeros(self.mapped.size_out(i)[::-1]) for i in range(function.n_out())]
        self.buffer, self.call = self.mapped.buffer()
        self.buffer.set_arg(0, memoryview(self.arg))
        for i, r in enumerate(self.res):
            self.buffer.set_res(i, memoryview(r))

    def __call__(self, q: np.ndarray) -> list:
        """Outputs at the m rows of q (m, N): each (m, rows, cols), views of the buffers."""
        self.arg[...] = q  # a column-major (N, m) buffer is the same memory as C-order (m, N)
        self.call()
        m = len(q)
        shapes = (self.function.size_out(i) for i in range(self.function.n_out()))
        # each output buffer holds m column-major (rows, cols) blocks side by side
        return [r.reshape(m, cols, rows).transpose(0, 2, 1) for r, (rows, cols) in
                zip(self.res, shapes)]


def _mapped(function: ca.Function, size: int) -> _Mapped:
    """The map of ``function`` over ``size`` poses with its buffers, kept in this thread (built
    here: CasADi's symbolic construction is not thread-safe, nor are shared buffers)."""
    maps = getattr(_LOCAL, "maps", None)
    if maps is None:
        maps = _LOCAL.maps = {}
    key = (id(function), size)
    if key not in maps or maps[key].function is not function:  # the Function, not a reused id
        if len(maps) >= _MAPS_KEPT:
            maps.pop(next(iter(maps)))
        maps[key] = _Mapped(function, size)
    return maps[key]


def map_poses(function: ca.Function, q: np.ndarray) -> list:
    """A Function of one pose, ``f(q) -> (y_1, …)``, at every row of q (M, N).

    Parameters
    ----------
    function : casadi.Function
        Of one pose (N,), each output (rows, cols).
    q : ndarray, shape (M, N)
        Poses, rad (m), evaluated in chunks of :data:`CHUNK`.

    Returns
    -------
    list of ndarray
        One per output, shape (M, rows, cols).

    Examples
    --------
    >>> x = ca.SX.sym("x", 2)
    >>> f = ca.Function("f", [x], [ca.vertcat(x[0] * x[1], x[0] + x[1])])
    >>> map_poses(f, np.array([[1.0, 2.0], [3.0, 4.0]]))[0][:, :, 0].tolist()
    [[2.0, 3.0], [12.0, 7.0]]
    """
    q = np.atleast_2d(np.asarray(q, float))
    m = len(q)
    size = min(CHUNK, m)  # every chunk this size, the last one padded with pose 0
    out = [np.empty((m, *function.size_out(i))) for i in range(function.n_out())]
    for start in range(0, m, size):
        stop, index = min(start + size, m), np.arange(start, start + size)
        for o, r in zip(out, _mapped(function, size)(q[np.where(index < m, index, 0)])):
            o[start:stop] = r[:stop - start]
    return out
