"""What the residual figures plot: each reading's residual norm and the variables it may follow.

Kept apart from :mod:`doe_calib.report` (and matplotlib) so that a command can
compute the figure's data while the figure itself is drawn elsewhere
(:mod:`doe_calib.report.figure_worker`).
"""
from __future__ import annotations

import numpy as np

from doe_calib.diagnosis.residuals import residuals
from doe_calib.diagnosis.variables import configuration_variables


def reading_columns(model, measurements) -> list[tuple]:
    """Variables to plot the residuals against, one value per reading (display units).

    Returns
    -------
    list of (str, ndarray of shape (K,))
        Every joint position (deg/mm), every wrench component that varies
        (N, N·m), the joint torques of the applied wrench (N·m), the
        temperature (°C) if measured, and the measurement order
        (:func:`doe_calib.diagnosis.variables.configuration_variables`).
    """
    c = measurements.config
    variables = configuration_variables(model.robot, measurements.configurations)
    return [(f"{name} ({unit})" if unit else name, v[c]) for name, (v, unit, _) in
            variables.items()]


def residual_norms_mm(model, measurements, values) -> np.ndarray:
    """3-D residual norm of each reading, shape (K,), mm (:func:`doe_calib.diagnosis.residuals`)."""
    return np.linalg.norm(residuals(model, measurements, values).error, axis=1) * 1000.0
