"""Independent tasks in parallel: local processes by default, a Dask cluster on request.

Monte-Carlo studies and design sweeps are many independent tasks. They run
through an existing engine, never a home-made one: :mod:`concurrent.futures`
process pools on this machine, or ``dask.distributed`` when the user names
a scheduler (``--scheduler tcp://host:8786``). Each task carries its own
seed (:func:`task_seeds`), so results do not depend on the engine, the
number of workers or the order in which tasks finish.
"""
from __future__ import annotations

import os

import numpy as np

from doe_calib.errors import DoeCalibError


def task_seeds(seed: int, n: int) -> list:
    """``n`` independent child seeds of ``seed`` (numpy SeedSequence), one per task."""
    return [int(s.generate_state(1)[0]) for s in np.random.SeedSequence(seed).spawn(n)]


def default_workers() -> int:
    """Worker processes on this machine: the CPUs this process may use."""
    try:
        return max(len(os.sched_getaffinity(0)), 1)
    except AttributeError:
        return max(os.cpu_count() or 1, 1)


def run_tasks(func, tasks, scheduler: str | None = None, workers: int | None = None,
              progress=None, connect_timeout: float = 10.0) -> list:
    """``[func(t) for t in tasks]``, computed in parallel; results in the order of ``tasks``.

    Parameters
    ----------
    func : callable
        A module-level function (it is sent to other processes by pickling).
    tasks : sequence
        Picklable arguments, one per task.
    scheduler : str, optional
        Address of a Dask scheduler (``tcp://host:8786``) to run on a cluster;
        ``None`` uses local processes.
    workers : int, optional
        Local processes (default: the CPUs available); 1 runs in this process.
    progress : callable, optional
        ``progress(done, total, "")`` after each finished task
        (:mod:`doe_calib.runtime.progress`).
    connect_timeout : float
        Seconds to wait for the Dask scheduler before giving up.
    """
    tasks = list(tasks)
    if scheduler:
        return _on_dask(func, tasks, scheduler, progress, connect_timeout)
    workers = default_workers() if workers is None else workers
    if workers <= 1 or len(tasks) <= 1:
        return _collected(((i, func(t)) for i, t in enumerate(tasks)), len(tasks), progress)
    from concurrent.futures import ProcessPoolExecutor, as_completed  # 15 ms: when used

    with ProcessPoolExecutor(max_workers=min(workers, len(tasks))) as pool:
        futures = {pool.submit(func, t): i for i, t in enumerate(tasks)}
        return _collected(((futures[f], f.result()) for f in as_completed(futures)),
                          len(tasks), progress)


def _collected(finished, n: int, progress) -> list:
    """The results of ``finished`` (task index, result) pairs in task order, each reported."""
    out = [None] * n
    for done, (i, result) in enumerate(finished, start=1):
        out[i] = result
        if progress:
            progress(done, n, "")
    return out


def _on_dask(func, tasks, scheduler, progress, connect_timeout) -> list:
    try:
        from distributed import Client
        from distributed import as_completed as dask_completed
    except ImportError:
        raise DoeCalibError("--scheduler needs Dask: pip install 'doe_calib[cluster]' "
                            "(dask[distributed])") from None
    try:
        client = Client(scheduler, timeout=f"{connect_timeout}s")
    except OSError as exc:
        raise DoeCalibError(f"cannot reach the Dask scheduler at {scheduler}: {exc}; start one "
                            f"with `dask scheduler` and `dask worker {scheduler}`") from None
    with client:
        futures = client.map(func, tasks, pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        return _collected(((index[f.key], f.result()) for f in dask_completed(futures)),
                          len(tasks), progress)
