"""Large evaluations split over threads of this process, bit for bit the serial result.

NumPy's batched matrix products and copies, and CasADi's evaluation, run
without Python's lock, so a large evaluation cut into independent parts
(poses, candidates) runs on every core in threads: the packed information of
20 000 candidates of the KR 270 (``design.relaxation.packed_information``)
takes 0.98 s on one thread and 0.52 s on two (``results/benchmarks.md``,
"Speed code kept"); a matrix-vector product split so gained nothing and is
plain. Each part is computed exactly as it is alone: the output is the
serial one, bit for bit. The threads are only used where they cannot
oversubscribe the machine: in the main thread of a process that is not a
pool's worker (its siblings use the other cores), and with BLAS on one
thread (as the command line sets it,
:func:`doe_calib.runtime.threads.single_threaded_blas`), since a BLAS that
runs its own threads already uses the cores.
"""
from __future__ import annotations

import sys
import threading

from doe_calib.runtime.parallel import default_workers
from doe_calib.runtime.threads import blas_on_one_thread


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
