"""Cross-validated RMS: how well a model predicts poses it was not fitted to.

Poses (all their load cases and markers together) are split into K folds;
the model is identified on K − 1 folds, starting from the full fit, and
predicts the marker positions of the held-out fold. The RMS of every
held-out coordinate's error (mm) is the cross-validated RMS. Unlike the
fit residual it rises when a model over-fits, so it can rank models with
different numbers of parameters.
"""
from __future__ import annotations


import numpy as np

from ..errors import DoeCalibError
from ..identify import identify_quietly
from .residuals import residuals


def pose_folds(measurements, k: int = 5, seed: int = 0) -> list[np.ndarray]:
    """Boolean masks over readings, one per fold, splitting the pose ids at random."""
    poses = np.array(list(dict.fromkeys(measurements.configurations.pose)))
    k = max(2, min(k, len(poses)))
    order = np.random.default_rng(seed).permutation(len(poses))
    fold_of = {poses[i]: n % k for n, i in enumerate(order)}
    of_reading = np.array([fold_of[measurements.configurations.pose[c]]
                           for c in measurements.config])
    return [of_reading == f for f in range(k)]


def validation_rms(model, values, measurements) -> float:
    """RMS (mm) of every coordinate's error when ``values`` predict ``measurements``."""
    return residuals(model, measurements, values).rms_mm


def cross_validated_rms(model, measurements, params, k: int = 5, seed: int = 0) -> float:
    """K-fold (by pose) cross-validated RMS of ``model``, mm; NaN when a fold cannot be fitted.

    ``params`` gives start values and which parameters are free (normally
    the fit on all data).
    """
    sq, n = 0.0, 0
    for held in pose_folds(measurements, k, seed):
        train, test = measurements.subset(~held), measurements.subset(held)
        try:
            fit = identify_quietly(model, train, params, register=False)
        except DoeCalibError:
            return float("nan")
        e = validation_rms(model, fit.parameters.values, test) / 1e3
        sq += e ** 2 * test.n_coordinates
        n += test.n_coordinates
    return float(np.sqrt(sq / n) * 1e3)
