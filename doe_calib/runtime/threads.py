"""How many threads the linear algebra library (BLAS) may use.

Our matrices are small (thousands of rows, tens of columns): a second BLAS
thread gains little, and on a machine whose other core is busy (a parallel
test run, a Monte-Carlo worker, a shared CI runner) OpenBLAS's spinning
threads make an SVD a hundred times slower. Commands therefore run BLAS on
one thread unless the user has chosen (``OMP_NUM_THREADS``,
``OPENBLAS_NUM_THREADS`` or ``MKL_NUM_THREADS`` set to a value); parallelism comes from
processes (:mod:`doe_calib.runtime.parallel`).
"""
from __future__ import annotations

import os

#: The variables through which BLAS is told its threads.
BLAS_THREADS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def blas_on_one_thread() -> bool:
    """Whether BLAS runs on one thread here: one of :data:`BLAS_THREADS` is set and every
    one set says 1 (as :func:`single_threaded_blas` leaves them)."""
    chosen = [os.environ[v].strip() for v in BLAS_THREADS if v in os.environ]
    return bool(chosen) and all(v == "1" for v in chosen)


def single_threaded_blas():
    """Limit BLAS to one thread for this process unless the environment says otherwise.

    The command line imports NumPy, SciPy and CasADi only when a command runs,
    after this call: the environment variables set here give every BLAS loaded
    later one thread (each reads them when it loads; child processes inherit
    them), and threadpoolctl limits those already loaded.

    Returns the threadpoolctl limiter (keep it alive), or None when the user chose.
    """
    if any(os.environ.get(v, "").strip() for v in BLAS_THREADS):  # an empty value chooses nothing
        return None
    os.environ.update({v: "1" for v in BLAS_THREADS})
    from threadpoolctl import threadpool_limits
    return threadpool_limits(limits=1, user_api="blas")
