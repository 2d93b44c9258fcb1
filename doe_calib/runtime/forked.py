"""Tasks over objects a pickle cannot carry (collision models), in forked worker processes.

A collision model holds coal geometry, which does not pickle: a process pool
of the usual kind cannot be sent it. A forked child has a copy of the parent's
memory, so it sees the model as the parent left it. :func:`forked_map` keeps the
shared objects in a module global while its pool of forked children works
through the task numbers, and returns the results (which do pickle) in order.
Where the platform cannot fork, one worker is asked for, or this process is a
daemon (a pool's or a Dask worker, which may not have children), the tasks run
in this process; the results are the same.
"""
from __future__ import annotations

import multiprocessing

from doe_calib.runtime.parallel import default_workers

#: What the running :func:`forked_map` shares with its children: (function, shared).
_RUNNING: tuple = ()


def forked_map(function, shared, n: int, workers: int | None = None) -> list:
    """``[function(shared, i) for i in range(n)]``, in ``workers`` forked processes.

    Parameters
    ----------
    function : callable
        ``function(shared, i)`` → a picklable result; a module-level function.
    shared : object
        What every task reads (not pickled: the children see it by the fork).
    n : int
        Tasks.
    workers : int, optional
        Processes (default: the CPUs this process may use; 1: in this process, as in a
        daemonic process).
    """
    workers = default_workers() if workers is None else max(1, int(workers))
    if (workers == 1 or n < 2 or multiprocessing.current_process().daemon
            or "fork" not in multiprocessing.get_all_start_methods()):
        return [function(shared, i) for i in range(n)]
    global _RUNNING
    _RUNNING = (function, shared)
    try:
        with multiprocessing.get_context("fork").Pool(min(workers, n)) as pool:
            return pool.map(_task, range(n), chunksize=1)
    finally:
        _RUNNING = ()


def _task(i: int):
    function, shared = _RUNNING
    return function(shared, i)
