"""The thread-split policy (:func:`split_workers`: one thread off the main thread, with BLAS
free to run its own threads, or in a pool's worker) and :func:`run_parts`.
"""
import threading

import pytest

from doe_calib.runtime.parallel import default_workers
from doe_calib.runtime.split import run_parts, split_workers
from doe_calib.runtime.threads import BLAS_THREADS


@pytest.fixture
def pinned(monkeypatch):
    """BLAS on one thread, as the command line sets it."""
    for v in BLAS_THREADS:
        monkeypatch.setenv(v, "1")


def test_threads_only_with_blas_on_one_thread_and_in_the_main_thread(pinned, monkeypatch):
    assert split_workers() == default_workers()
    seen = []
    worker = threading.Thread(target=lambda: seen.append(split_workers()))
    worker.start()
    worker.join()
    assert seen == [1]  # a thread that splits again would oversubscribe the cores
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "4")  # BLAS runs its own threads
    assert split_workers() == 1
    for v in BLAS_THREADS:
        monkeypatch.delenv(v)  # BLAS's default: every core
    assert split_workers() == 1


def test_parts_run_at_once_in_order():
    together = threading.Barrier(3, timeout=10)  # passed only by three threads at once

    def part(i):
        together.wait()
        return i, threading.current_thread().name

    names = run_parts(part, range(3))
    assert [i for i, _ in names] == [0, 1, 2]
    assert names[0][1] == threading.current_thread().name  # the first in the caller
    assert len({n for _, n in names}) == 3
    assert run_parts(lambda i: i + 1, [4]) == [5]
    assert run_parts(lambda i: i, []) == []

