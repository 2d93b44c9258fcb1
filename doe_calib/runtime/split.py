"""Large evaluations split over threads of this process, bit for bit the serial result.

NumPy's matrix products and copies, and CasADi's evaluation, run without
Python's lock, so a large evaluation cut into independent parts (poses,
candidates) runs on every core in threads. Each part is computed exactly as
it is alone: the output is the serial one, bit for bit. The threads are only
used where they cannot oversubscribe the machine: in the main thread of a
process that is not a pool's worker (its siblings use the other cores), and
with BLAS on one thread (as the command line sets it,
:func:`doe_calib.runtime.threads.single_threaded_blas`), since a BLAS that
runs its own threads already uses the cores.
"""
from __future__ import annotations

import sys
import threading

import numpy as np

from doe_calib.runtime.parallel import default_workers
from doe_calib.runtime.threads import blas_on_one_thread

#: Entries of the matrix each thread of :func:`matvec` takes at least: a smaller share takes
#: under half a millisecond, about what handing work to a thread and back costs.
MIN_PART = 2_000_000
#: Rows of each part a multiple of this: BLAS kernels take rows in groups (4 or 8), and a
#: row computed in another group would be rounded otherwise.
ALIGN = 64


def split_workers() -> int:
    """Threads a large evaluation may be split over here; 1: evaluate it serially.

    The CPUs this process may use (:func:`.parallel.default_workers`) when it
    runs in the main thread of a process that is no pool's worker and BLAS is
    on one thread (every one of ``OMP_NUM_THREADS``, ``OPENBLAS_NUM_THREADS``
    and ``MKL_NUM_THREADS`` that is set says 1, and one is set); else 1.

    Examples
    --------
    >>> split_workers() >= 1
    True
    """
    if not blas_on_one_thread():
        return 1
    if threading.current_thread() is not threading.main_thread():
        return 1
    pools = sys.modules.get("multiprocessing")  # a pool's worker has it imported
    if pools is not None and pools.parent_process() is not None:
        return 1
    return default_workers()


def run_parts(func, parts) -> list:
    """``[func(part) for part in parts]``, the parts computed at once in threads.

    The first part runs in the calling thread, the others in as many threads;
    ``func`` must only evaluate (CasADi's symbolic construction is not
    thread-safe: build before) and write to memory no other part reads.

    Parameters
    ----------
    func : callable
    parts : sequence
        One argument per thread (e.g. from :func:`split_workers` many).

    Returns
    -------
    list
        The results, in the order of ``parts``.
    """
    parts = list(parts)
    if len(parts) <= 1:
        return [func(p) for p in parts]
    from concurrent.futures import ThreadPoolExecutor  # imported when threads are used

    with ThreadPoolExecutor(len(parts) - 1) as pool:
        futures = [pool.submit(func, p) for p in parts[1:]]
        first = func(parts[0])
        return [first] + [f.result() for f in futures]


def matvec(a: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``a @ x``, bit for bit, its rows shared out to threads when ``a`` is large.

    Each output element is the same dot product whichever thread computes it.
    The parts are a multiple of :data:`ALIGN` rows, each of at least
    :data:`MIN_PART` entries, as many as :func:`split_workers` allows; with
    fewer than two such parts, or ``a`` not C-ordered, the plain product.

    Parameters
    ----------
    a : ndarray, shape (M, K)
    x : ndarray, shape (K,)

    Returns
    -------
    ndarray, shape (M,)

    Examples
    --------
    >>> a = np.arange(6.0).reshape(3, 2)
    >>> matvec(a, np.array([1.0, -1.0])).tolist()
    [-1.0, -1.0, -1.0]
    """
    workers = min(split_workers(), a.size // MIN_PART) if a.size >= 2 * MIN_PART else 1
    if workers <= 1 or a.ndim != 2 or x.ndim != 1 or not a.flags.c_contiguous:
        return a @ x
    step = -(-len(a) // (workers * ALIGN)) * ALIGN
    out = np.empty(len(a), np.result_type(a, x))
    run_parts(lambda s: np.matmul(a[s:s + step], x, out=out[s:s + step]),
              range(0, len(a), step))
    return out
