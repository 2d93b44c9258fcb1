"""Simulated campaigns with a hidden effect: poses, ±loads, temperatures, tracker anywhere."""
from __future__ import annotations

import numpy as np

from doe_calib import Configurations, simulate
from doe_calib.model.loads import hanging_mass_wrench
from doe_calib.model.simulate import random_configurations

SIGMA_M = 3e-5
LOAD_KG, LOAD_COM_M = 250.0, (0.0, 0.0, 0.2)


def campaign(model, truth, robot, n, rng, drift_m: float = 0.0):
    """``n`` poses, each unloaded, with the load hung on, and pulled the other way.

    Temperatures are drawn in 15–35 °C per pose; ``drift_m`` adds a tracker
    drift growing linearly with the measurement order (an effect outside the
    catalogue).
    """
    q = np.repeat(random_configurations(robot, n, rng), 3, axis=0)
    w = np.zeros((3 * n, 6))
    w[1::3] = hanging_mass_wrench(model, truth, q[1::3], LOAD_KG, LOAD_COM_M)
    w[2::3] = -w[1::3]
    temp = np.repeat(rng.uniform(15, 35, n), 3)[:, None]
    cfg = Configurations.from_arrays(q, w, temp, pose=np.repeat(np.arange(n) + 1, 3))
    meas = simulate(model, truth, cfg, SIGMA_M, rng)
    if drift_m:
        meas.xyz[:] += drift_m * (meas.config / len(cfg))[:, None] * np.array([1.0, -0.5, 0.3])
    return meas
