"""Commands run BLAS on one thread unless the user chose a number (runtime/threads.py), seen in
a fresh interpreter: its environment and threadpoolctl's report of the loaded BLAS."""
import json
import os

import pytest
from fresh_interpreter import run_python

PROBE = """
import json, os
from doe_calib.runtime.threads import single_threaded_blas
limiter = single_threaded_blas()
import numpy
from threadpoolctl import threadpool_info
blas = [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"]
print(json.dumps({"env": os.environ.get("OPENBLAS_NUM_THREADS"), "blas": blas,
                  "limited": limiter is not None}))
"""


def _probe(**env) -> dict:
    clean = {k: v for k, v in os.environ.items()
             if k not in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}
    out = run_python(PROBE, env={**clean, **env})
    return json.loads(out.strip().splitlines()[-1])


@pytest.mark.parametrize("env", [{}, {"OPENBLAS_NUM_THREADS": ""},
                                 {"OMP_NUM_THREADS": " "}])
def test_unset_or_empty_means_one_thread(env):
    got = _probe(**env)
    assert got["limited"] and got["env"] == "1"
    assert got["blas"] and all(n == 1 for n in got["blas"])


def test_a_number_the_user_chose_is_kept():
    got = _probe(OPENBLAS_NUM_THREADS="2")
    assert not got["limited"] and got["env"] == "2"
