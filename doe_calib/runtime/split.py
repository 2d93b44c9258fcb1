"""Large evaluations split over threads of this process, bit for bit the serial result.

NumPy's batched products and CasADi's evaluation run without Python's lock, so
independent parts (poses, candidates) of a large evaluation run on every core
in threads (timings: ``results/benchmarks.md``, "Speed code kept"). Threads are
used only where they cannot oversubscribe the machine: in the main thread of a
process that is not a pool's worker, with BLAS on one thread
(:func:`doe_calib.runtime.threads.single_threaded_blas`).
"""
from __future__ import annotations

import sys
import threading

from doe_calib.runtime.parallel import default_workers
from doe_calib.runtime.threads import blas_on_one_thread


def split_workers() -> int:
    """Threads a large evaluation may be split over here (module notes); 1: evaluate serially.

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
    """``[func(part) for part in parts]``, the first part in this thread, the others in threads.

    ``func`` must only evaluate (CasADi's symbolic construction is not
    thread-safe: build before) and write to memory no other part reads.
    """
    parts = list(parts)
    if len(parts) <= 1:
        return [func(p) for p in parts]
    from concurrent.futures import ThreadPoolExecutor  # imported when threads are used

    with ThreadPoolExecutor(len(parts) - 1) as pool:
        futures = [pool.submit(func, p) for p in parts[1:]]
        first = func(parts[0])
        return [first] + [f.result() for f in futures]
