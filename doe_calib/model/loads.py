"""Load cases: the wrench at the flange of a mass hanging from the tool."""
from __future__ import annotations

import numpy as np

from doe_calib.io.measurements import Configurations
from doe_calib.model.evaluation import evaluate

GRAVITY = 9.80665  # m/s²


def hanging_mass_wrench(model, values, q, mass: float, com) -> np.ndarray:
    """Wrench (N, N·m) at the flange origin, robot base frame, of a mass on the flange.

    Parameters
    ----------
    model : Model
    values : array_like, shape (P,)
        Parameters used to place the flange (SI); deflection is neglected.
    q : array_like, shape (M, N)
        Joint positions, rad/m.
    mass : float
        kg.
    com : array_like, shape (3,)
        Centre of mass in the flange frame, metres.

    Returns
    -------
    ndarray, shape (M, 6)
        ``(fx, fy, fz, mx, my, mz)``; gravity is −z of the robot base frame.
    """
    cfg = Configurations.from_arrays(q)
    (origin, _) = evaluate(model.point_robot, cfg, values, np.zeros(3))
    (centre, _) = evaluate(model.point_robot, cfg, values, np.asarray(com, float))
    force = np.array([0.0, 0.0, -mass * GRAVITY])
    arm = (centre - origin)[:, :, 0]
    return np.hstack([np.tile(force, (len(cfg), 1)), np.cross(arm, force)])


def unloaded_and_loaded(model, values, q, mass: float, com, pose=None) -> Configurations:
    """Each pose measured unloaded, then with the mass hung on: 2M configurations.

    A zero mass is no load: the M unloaded configurations only (the loaded ones
    would repeat them, and a file cannot hold one reading twice).
    """
    q = np.atleast_2d(np.asarray(q, float))
    m = q.shape[0]
    if mass == 0:
        ids = None if pose is None else [str(p) for p in pose]
        return Configurations.from_arrays(q, pose=ids)
    w = np.zeros((2 * m, 6))
    w[1::2] = hanging_mass_wrench(model, values, q, mass, com)
    ids = [str(i + 1) for i in range(m)] if pose is None else [str(p) for p in pose]
    return Configurations.from_arrays(np.repeat(q, 2, axis=0), w, pose=np.repeat(ids, 2))
