"""Numeric evaluation of a model's Functions for many configurations at once.

Each Function is mapped over the M configurations with ``Function.map`` (one
call, no Python loop over poses; "serial": CasADi's "thread" map starts a
thread per pose, which costs more than the work, see benchmarks/) and
evaluated through CasADi's zero-copy
buffers, so numpy arrays go in and out without DM conversion. Mapped
Functions and their buffers live in a :class:`Workspace`, owned by the
caller or, by default, one per thread: a Dask worker running several tasks
at once never shares a buffer. A compiled model's observation runs on L
configurations per call (``Model.observation_lanes``, the SIMD lanes of
:mod:`doe_calib.model.simd_code`): ⌈M/L⌉ calls, the same numbers.
"""
from __future__ import annotations

import threading
from collections import OrderedDict

import casadi as ca
import numpy as np

_LOCAL = threading.local()
_CACHE_SIZE = 64
_CACHE_BYTES = 256 * 2 ** 20


class _Batch:
    """A Function mapped over M configurations, with preallocated numpy buffers.

    With ``lanes`` (the Function on L configurations side by side, same layout)
    that is mapped over ⌈M/L⌉ calls; configurations of zeros fill the last
    call, their results dropped.
    """

    def __init__(self, function: ca.Function, m: int, shared: tuple, lanes=None):
        # inputs q, w, env vary per configuration; p and the `shared` extra inputs do not. The
        # plain map takes every input per call (the shared ones' buffers hold a copy per call):
        # a map that repeats them itself is a wrapper built in time and memory ∝ M (1.4 s for
        # 33 000 configurations), the plain one at once
        self.unit = lanes if lanes is not None and m > 1 else function
        calls = -(-m // self.unit.size_in(0)[1])  # q is N × L on L lanes
        self.mapped = self.unit.map(calls, "serial") if calls > 1 else self.unit
        self.m, self.shared = m, frozenset(shared)
        self.args = [np.zeros(self.mapped.size_in(i)[::-1]) for i in range(self.mapped.n_in())]
        self.res = [np.zeros(self.mapped.size_out(i)[::-1]) for i in range(self.mapped.n_out())]
        self.shapes = [function.size_out(i) for i in range(function.n_out())]
        self.nbytes = sum(a.nbytes for a in self.args + self.res)
        self.buffer, self.call = self.mapped.buffer()
        for i, a in enumerate(self.args):
            self.buffer.set_arg(i, memoryview(a))
        for i, r in enumerate(self.res):
            self.buffer.set_res(i, memoryview(r))

    def __call__(self, inputs) -> list:
        # Column-major (k, M) buffers are the same memory as C-order (M, k) arrays.
        for i, (a, x) in enumerate(zip(self.args, inputs)):
            x = np.asarray(x, float).reshape(a.shape[1:] if i in self.shared else (-1, a.shape[1]))
            if i in self.shared:
                a[...] = x  # one copy per call
            else:  # M not a multiple of the lanes: the last rows stay zero
                a[:len(x)] = x
        self.call()
        # Each output buffer holds M column-major (rows, cols) blocks side by side.
        return [r.reshape(-1, cols, rows)[:self.m].transpose(0, 2, 1).copy()
                for r, (rows, cols) in zip(self.res, self.shapes)]


class Workspace:
    """Scratch memory for evaluating Functions: mapped Functions and their buffers.

    The model says what to compute; a workspace is where it is computed (as
    Pinocchio's ``Model`` and ``Data``). Batches are kept per (Function, M),
    the least recently used dropped beyond a count or a total buffer size
    (diagnosis builds a model per candidate effect: their buffers must not
    pile up). A workspace must not be used by two threads at once; without
    one, each thread gets its own (:func:`thread_workspace`).
    """

    def __init__(self):
        self._batches = OrderedDict()

    def batch(self, function: ca.Function, m: int, shared: tuple, lanes=None) -> _Batch:
        """The Function mapped over ``m`` configurations, made on first use; L at a time
        with ``lanes`` (the Function on L configurations side by side)."""
        key = (id(function), id(lanes), m, shared)
        hit = self._batches.get(key)
        if hit is not None and hit[0] is function and hit[1] is lanes:  # not a reused id
            self._batches.move_to_end(key)
            return hit[2]
        batch = _Batch(function, m, shared, lanes)
        self._batches[key] = (function, lanes, batch)
        while len(self._batches) > 1 and (len(self._batches) > _CACHE_SIZE or
                                          self.nbytes > _CACHE_BYTES):
            self._batches.popitem(last=False)
        return batch

    @property
    def nbytes(self) -> int:
        """Bytes held in buffers."""
        return sum(b.nbytes for _, _, b in self._batches.values())


def thread_workspace() -> Workspace:
    """The calling thread's own default workspace."""
    ws = getattr(_LOCAL, "workspace", None)
    if ws is None:
        ws = _LOCAL.workspace = Workspace()
    return ws


def evaluate(function: ca.Function, configurations, values, *extra, workspace=None,
             lanes=None):
    """Evaluate a model Function at every configuration.

    Parameters
    ----------
    function : casadi.Function
        One of a :class:`~doe_calib.model.marker_model.Model`'s Functions, with inputs
        ``(q, w, env, p, *extra)``.
    configurations : Configurations
        M configurations (q in rad/m, wrench in N/N·m).
    values : array_like, shape (P,)
        Parameter values, SI.
    *extra : array_like
        Further inputs: 1-D arrays are shared by every configuration (e.g. a
        point ``t``, m); 2-D arrays of shape (M, k) give one row per configuration.
    workspace : Workspace, optional
        Where to evaluate; default the calling thread's own.
    lanes : casadi.Function, optional
        ``function`` on L configurations side by side (a model's
        ``observation_lanes``): evaluated ⌈M/L⌉ times instead, same results.

    Returns
    -------
    list of ndarray
        One array per output, shape (M, rows, cols).
    """
    extra = [np.asarray(e, float) for e in extra]
    shared = (3,) + tuple(4 + i for i, e in enumerate(extra) if e.ndim == 1)
    inputs = [configurations.q, configurations.wrench, configurations.env, values, *extra]
    ws = thread_workspace() if workspace is None else workspace
    return ws.batch(function, len(configurations), shared, lanes)(inputs)


def marker_positions(model, values, configurations, workspace=None) -> np.ndarray:
    """Marker positions in the tracker frame, shape (M, n, 3), metres."""
    (x,) = evaluate(model.markers, configurations, values, workspace=workspace)
    return x.reshape(len(configurations), model.tool.n_markers, 3)


def observation_matrix(model, values, configurations, workspace=None):
    """Marker positions (M, n, 3) m and observation matrix B = ∂x/∂p, shape (M, n, 3, P)."""
    x, b = evaluate(model.observation, configurations, values, workspace=workspace,
                    lanes=model.observation_lanes)
    m, n = len(configurations), model.tool.n_markers
    return x.reshape(m, n, 3), b.reshape(m, n, 3, -1)
