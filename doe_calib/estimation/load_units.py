"""A wrench written in kgf (or as a mass in kg) where newtons are due, told after the fit.

The data fix only the product of a compliance and the load: a wrench 9.80665×
too small gives compliances 9.80665× too large, and the fit is as good. The
robot tells which is plausible. Its URDF states each joint's effort limit
τ_max; a gearbox and its bearings yield some tenths of a degree at τ_max
(an industrial arm's RV reducer or a cobot's harmonic drive alike), so a
fitted compliance ``c`` whose twist ``c · τ_max`` passes a degree or more is
implausible for the joint. A calibration load is chosen to load the joints:
its torques ``τ = J_θᵀ F`` reach a good share of τ_max, where a load in kgf
reaches a tenth of that. The finding is made when the twist is far beyond
plausible (:data:`TWIST_FAR_DEG`), or beyond it (:data:`TWIST_DEG`) with a
load that reaches less than :data:`LOAD_SHARE` of the effort limits.
"""
from __future__ import annotations

import numpy as np

#: g_n, N per kgf.
KGF = 9.80665
#: Twist of a joint at its effort limit (deg) beyond which its compliance is implausible.
TWIST_DEG = 1.0
#: Twist at the effort limit (deg) implausible whatever the load.
TWIST_FAR_DEG = 5.0
#: A load whose largest joint torque stays below this share of the effort limit is light.
LOAD_SHARE = 0.10
#: A compliance counts by its value less this many standard deviations.
STDS = 2.0


def twists_at_effort(params, std, robot) -> list:
    """Joints whose fitted compliance twists them past :data:`TWIST_DEG` at their effort limit.

    Parameters
    ----------
    params : ParameterSet
        Fitted values, SI.
    std : ndarray, shape (P,)
        Their standard deviations, SI.
    robot : Robot
        Gives each joint's effort limit (N·m; 0: not stated, the joint is skipped).

    Returns
    -------
    list of (Joint, float)
        The joint and its twist at the effort limit, deg (value less :data:`STDS` std),
        largest first.
    """
    out = []
    for j in robot.joints:
        name = f"k_{j.name}"
        if j.kind != "revolute" or j.effort <= 0 or name not in params.names:
            continue
        i = params.index([name])[0]
        if not params.free[i]:
            continue
        twist = np.degrees((params.values[i] - STDS * std[i]) * j.effort)
        if twist > TWIST_DEG:
            out.append((j, float(twist)))
    return sorted(out, key=lambda x: -x[1])


def load_share(robot, configurations) -> float:
    """Largest ``|τ_k| / τ_max,k`` over configurations and revolute joints with an effort limit,
    τ = J_θᵀ F of the file's wrench on the nominal chain (NaN when no joint states a limit)."""
    from doe_calib.model.kinematics import nominal_torque_function

    limits = np.array([j.effort if j.kind == "revolute" else 0.0 for j in robot.joints])
    if not (limits > 0).any() or not len(configurations):
        return float("nan")
    tau = np.array(nominal_torque_function(robot).map(len(configurations))(
        configurations.q.T, configurations.wrench.T)).T
    return float(np.max(np.abs(tau[:, limits > 0]) / limits[limits > 0]))


def kgf_finding(params, std, robot, configurations) -> str | None:
    """Words naming the wrench columns as kgf when the compliances say so (module notes).

    Parameters
    ----------
    params : ParameterSet
    std : ndarray, shape (P,)
    robot : Robot
    configurations : Configurations
        The loads as read (N, N·m).

    Returns
    -------
    str or None
    """
    forces = np.linalg.norm(configurations.wrench[:, :3], axis=1)
    if not len(forces) or forces.max() <= 0:
        return None
    soft = twists_at_effort(params, std, robot)
    if not soft:
        return None
    joint, twist = soft[0]
    share = load_share(robot, configurations)
    if twist < TWIST_FAR_DEG and not share < LOAD_SHARE:
        return None
    if twist / KGF > TWIST_DEG * 2:  # even 9.8× less stays implausible: not a unit
        return None
    at = int(np.argmax(forces))
    return (f"the wrench columns (fx, fy, fz, mx, my, mz) look like kgf (or a mass in kg), not "
            f"N and N·m: the fitted compliance of joint {joint.name} twists it by {twist:.3g}° "
            f"at its effort limit ({joint.effort:g} N·m in the URDF), where a joint yields some "
            f"tenths of a degree (≲ {TWIST_DEG:g}°), and the loads reach only "
            f"{100 * share:.2g} % of the joints' effort limits; the largest force, "
            f"{forces[at]:.4g} (pose {configurations.pose[at]}), would be the weight of "
            f"{forces[at] / KGF:.3g} kg in N, of {forces[at]:.4g} kg in kgf. Multiply the six "
            f"wrench columns by {KGF} (the compliances then come out {KGF}× smaller)")
