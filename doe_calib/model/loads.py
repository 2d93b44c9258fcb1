"""Load cases: the wrench at the flange of a mass hanging from the tool."""
from __future__ import annotations

import numpy as np

from doe_calib.io.measurements import Configurations
from doe_calib.model.evaluation import evaluate
from doe_calib.model.kinematics import payload_torque_function
from doe_calib.model.simulate import random_configurations

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


#: Poses sampled inside the limits to judge a payload against the joints' effort limits.
EFFORT_SAMPLES = 256


def payload_beyond_effort(robot, mass: float, com, rng=None) -> str | None:
    """Words for a payload far beyond the URDF's effort limits, or None.

    The payload's own torque ``τ = J_θᵀ F`` (nominal chain) is taken over
    :data:`EFFORT_SAMPLES` random poses inside the limits; a payload whose
    median torque at some joint exceeds that joint's ``<limit effort>`` is
    one the arm cannot hold in most of its workspace. Joints without an
    effort limit are not judged.

    Parameters
    ----------
    robot : Robot
    mass : float
        kg.
    com : array_like, shape (3,)
        Centre of mass in the flange frame, m.
    rng : numpy.random.Generator, optional
        Draws the poses (default: a fixed seed, so the verdict is repeatable).

    Returns
    -------
    str or None
        The joint, the torque the payload needs there (median and largest over
        the poses, N·m or N) and its effort limit.
    """
    effort = np.array([j.effort for j in robot.joints])
    if mass <= 0 or not np.any(effort > 0):
        return None
    rng = np.random.default_rng(0) if rng is None else rng
    q = random_configurations(robot, EFFORT_SAMPLES, rng, margin=0.0)
    tau = np.abs(np.array(payload_torque_function(robot).map(len(q))(
        q.T, float(mass), np.asarray(com, float)))).T
    need = np.median(tau, axis=0)
    over = np.flatnonzero((effort > 0) & (need > effort))
    if not over.size:
        return None
    k = over[np.argmax(need[over] / effort[over])]
    j = robot.joints[k]
    unit = "N·m" if j.kind == "revolute" else "N"
    return (f"a payload of {mass:g} kg needs {need[k]:.4g} {unit} at joint {j.name} in half the "
            f"poses (up to {tau[:, k].max():.4g} {unit}), while the URDF's effort limit of that "
            f"joint is {effort[k]:.4g} {unit}: far beyond what the arm can hold (the mass in kg? "
            f"the right robot?)")

