"""Evaluations split over threads give the serial numbers, bit for bit.

The policy (:func:`split_workers`: one thread off the main thread, with BLAS
free to run its own threads, or in a pool's worker), :func:`run_parts`, and
each threaded path against its serial run: the pose maps (several chunks),
the packed information (several chunks) and the relaxation built on it.
"""
import threading

import casadi as ca
import numpy as np
import pytest
from numpy.testing import assert_array_equal

from doe_calib.design.batch import CHUNK, map_poses
from doe_calib.design.solvers.relaxation import packed_information, relax
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


def test_pose_map_in_threads_is_the_serial_one():
    q = ca.SX.sym("q", 3)
    f = ca.Function("f", [q], [ca.horzcat(ca.sin(q[0]) * q[1], ca.exp(q[2]) / (1 + q[1] ** 2)),
                               ca.cos(q[0] * q[2])])
    poses = np.random.default_rng(7).normal(size=(3 * CHUNK + 5, 3))  # four chunks, one padded
    serial = map_poses(f, poses, workers=1)
    for workers in (2, 3, 8):
        for a, b in zip(map_poses(f, poses, workers=workers), serial):
            assert_array_equal(a, b)


def test_packed_information_and_relaxation_in_threads_are_the_serial_ones():
    blocks = np.random.default_rng(8).normal(size=(3000, 6, 9))  # three chunks of candidates
    serial = packed_information(blocks, workers=1)
    for workers in (2, 3, 5):
        assert_array_equal(packed_information(blocks, workers=workers), serial)
    out = np.empty((3010, serial.shape[1]))
    packed_information(blocks, out=out[:3000], workers=2)  # into rows of a larger array
    assert_array_equal(out[:3000], serial)
    a = relax(None, packed=serial)
    b = relax(None, packed=packed_information(blocks, workers=2))
    assert_array_equal(a.weights, b.weights)
    assert a.value == b.value and a.ratio == b.ratio and a.iterations == b.iterations
