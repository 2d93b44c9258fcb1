"""Tasks over objects a pickle cannot carry (collision models), in forked worker processes.

A collision model holds coal geometry, which does not pickle: a process pool
of the usual kind cannot be sent it. A forked child has a copy of the parent's
memory, so it sees the model as the parent left it. :func:`forked_pool` keeps the
shared objects in a module global while its forked children work through the
tasks handed to them (each a picklable item: a task number, or what a task
learnt from the caller's work since the fork), and returns the results (which do
pickle) in order, each as soon as it is done, while the caller goes on with its
own work; :func:`forked_map` maps over task numbers. Where the platform cannot
fork, no forked process is asked for (one worker, for :func:`forked_map`), or this
process is a daemon (a pool's or a Dask worker, which may not have children), the
tasks run in this process, each when its result is asked for; the results are the
same.
"""
from __future__ import annotations

import multiprocessing
from contextlib import contextmanager

from doe_calib.runtime.parallel import default_workers

#: What the open :func:`forked_pool` shares with its children.
_SHARED: tuple = ()


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
    with forked_pool(shared, min(workers, n) if workers > 1 and n > 1 else 0) as results:
        return list(results(function, range(n)))


@contextmanager
def forked_pool(shared, processes: int | None = None):
    """Forked processes sharing ``shared``, for tasks handed to them while the caller works.

    Yields ``results(function, items)``: an iterator over ``function(shared, item)`` for
    each item, in the order of ``items``, computed ahead in the processes (in this
    process, each when asked for, where they cannot be forked or ``processes`` is 0).

    Parameters
    ----------
    shared : object
        What every task reads (not pickled: the children see it as it was at the fork).
    processes : int, optional
        Forked processes (default: the CPUs this process may use); 0: none.

    Examples
    --------
    >>> with forked_pool((2.0,), processes=1) as results:  # doctest: +SKIP
    ...     squares = results(_scaled_square, range(5))  # computed while this process works
    ...     first = next(squares)
    """
    processes = default_workers() if processes is None else max(0, int(processes))
    if (not processes or multiprocessing.current_process().daemon
            or "fork" not in multiprocessing.get_all_start_methods()):
        yield lambda function, items: (function(shared, item) for item in items)
        return
    global _SHARED
    before, _SHARED = _SHARED, shared
    try:
        with multiprocessing.get_context("fork").Pool(processes) as pool:
            yield lambda function, items: pool.imap(_task, ((function, i) for i in items), 1)
    finally:
        _SHARED = before


def _task(job):
    function, item = job
    return function(_SHARED, item)
