"""(c) Table-I-size Monte Carlo: identifications per second on the 3-DOF robot.

The paper's 3-DOF manipulator, 6 free parameters (three lengths, three
offsets), 3 configurations, σ = 0.01 mm; each replication simulates new
noise and identifies. Only ``identify`` is timed.
"""
from __future__ import annotations

import time

import numpy as np

from doe_calib import Configurations, identify, simulate

from ._common import Row, Section, models, quiet

NAMES = ["g_q2_tz", "g_q3_tx", "g_flange_tx", "dq_q1", "dq_q2", "dq_q3"]
SIGMA = 1e-5


def _problem(model):
    p0 = model.nominal().only(NAMES)
    truth = p0.updated(g_q2_tz=3e-3, g_q3_tx=2e-3, g_flange_tx=5e-3, dq_q1=np.radians(1),
                       dq_q2=np.radians(0.5), dq_q3=np.radians(2))
    cfg = Configurations.from_arrays(np.random.default_rng(3).uniform(-np.pi, np.pi, (3, 3)))
    return p0, truth, cfg


def rate(model, estimator: str, n_reps: int):
    """Identifications per second over ``n_reps`` replications."""
    p0, truth, cfg = _problem(model)
    rng = np.random.default_rng(21)
    data = [simulate(model, truth, cfg, SIGMA, rng) for _ in range(n_reps)]
    with quiet():
        identify(model, data[0], p0, estimator=estimator)
        t0 = time.perf_counter()
        for meas in data:
            identify(model, meas, p0, estimator=estimator)
        seconds = time.perf_counter() - t0
    return n_reps / seconds


def run(quick: bool = False) -> Section:
    ms = models()
    n_reps = 20 if quick else 200
    rows, figures = [], {}
    for estimator in ("point", "pose"):
        for tag, model in (("SX virtual machine", ms.vm3), ("compiled", ms.compiled3)):
            r = rate(model, estimator, n_reps)
            figures[estimator, tag] = r
            rows.append((f"{estimator}, {tag}", r))
    ref = figures["point", "compiled"]
    out = tuple(Row(case, r, "identifications/s", r / ref) for case, r in rows)
    notes = (f"{n_reps} replications per row; 3 configurations × 3 markers, "
             f"{len(NAMES)} free parameters, σ = {SIGMA * 1e3:g} mm.",
             "the pose estimator's flange-pose error function is built from the SX flange "
             "function and is not compiled; only its start-up (registration, rank analysis) "
             "uses the compiled functions.")
    return Section("(c) Monte Carlo, 3-DOF robot (Table I size)", out, "point, compiled", notes)
