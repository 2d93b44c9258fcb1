"""What the residual follows: the variables of each configuration and a smooth-fit test.

The variables: joint angles (deg; mm for prismatic joints), applied wrench
components (N, N·m), the joint torques they cause and those of the robot's own
weight (N·m, when the URDF gives masses), temperature (°C, when measured), each
joint's approach direction (±1, when it varies) and the measurement order. A
variable that varies only by round-off next to its family is left out. The
residual size per configuration (mean r² over its readings) is fitted by a
smooth function of each (angles: a line and one and two harmonics; others: a
cubic); the adjusted R² says how much of its variation that variable explains.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from doe_calib.model.kinematics import gravity_torque_function, nominal_torque_function

#: A variable varies when its spread exceeds this fraction of its family's largest value.
RELATIVE_SPREAD = 1e-6


@dataclass(frozen=True)
class Follows:
    """How strongly the residual size follows one variable."""

    variable: str
    unit: str
    r2: float
    direction: str

    def to_dict(self) -> dict:
        return asdict(self)


def configuration_variables(robot, configurations) -> dict:
    """Variable name → (values per configuration, unit, is_angle)."""
    out = {}
    revolute = [j.kind == "revolute" for j in robot.joints]
    for k, j in enumerate(robot.joints):
        factor = np.degrees(1.0) if revolute[k] else 1e3
        out[f"q{k + 1} ({j.name})"] = (configurations.q[:, k] * factor,
                                       "deg" if revolute[k] else "mm", revolute[k])
    w = configurations.wrench
    if np.any(w != 0):
        for i, name in enumerate(("force fx", "force fy", "force fz", "moment mx", "moment my",
                                  "moment mz")):
            if _varies(w[:, i], w[:, :3] if i < 3 else w[:, 3:]):
                out[name] = (w[:, i], "N" if i < 3 else "N·m", False)
        tau_f = nominal_torque_function(robot).map(len(configurations))
        tau = np.array(tau_f(configurations.q.T, w.T)).T
        for k, j in enumerate(robot.joints):
            if _varies(tau[:, k], tau):
                out[f"tau{k + 1} ({j.name})"] = (tau[:, k], "N·m" if revolute[k] else "N", False)
    if robot.has_inertials:
        tau_g = np.array(gravity_torque_function(robot).map(len(configurations))(
            configurations.q.T)).T
        for k, j in enumerate(robot.joints):
            if _varies(tau_g[:, k], tau_g):
                out[f"weight torque {k + 1} ({j.name})"] = (tau_g[:, k],
                                                            "N·m" if revolute[k] else "N", False)
    t = configurations.temperature
    if np.all(np.isfinite(t)) and np.ptp(t) > 0:
        out["temperature"] = (t, "°C", False)
    for k, j in enumerate(robot.joints):
        a = configurations.approach[:, k]
        if np.ptp(a) > 0:
            out[f"approach of q{k + 1} ({j.name})"] = (a, "", False)
    out["measurement order"] = (np.arange(len(configurations), dtype=float), "", False)
    return out


def reading_columns(model, measurements) -> list[tuple]:
    """The variables of :func:`configuration_variables` as one value per reading, labelled
    with their unit: ``[(label, ndarray of shape (K,)), …]`` (what the residual figures
    plot against)."""
    variables = configuration_variables(model.robot, measurements.configurations)
    return [(f"{name} ({unit})" if unit else name, v[measurements.config])
            for name, (v, unit, _) in variables.items()]


def _varies(v: np.ndarray, family: np.ndarray) -> bool:
    """Whether ``v`` spreads more than round-off next to the largest value of its family."""
    return bool(np.ptp(v) > RELATIVE_SPREAD * max(float(np.abs(family).max()), 1e-300))


def smooth_basis(v: np.ndarray, is_angle: bool) -> np.ndarray:
    """Columns of a smooth fit in ``v``: harmonics of an angle in deg (``is_angle``),
    else low-order polynomials of the standardised value."""
    if is_angle:
        a = np.radians(v)
        return np.column_stack([np.ones_like(a), a, np.sin(a), np.cos(a), np.sin(2 * a),
                                np.cos(2 * a)])
    z = (v - v.mean()) / (v.std() or 1.0)
    return np.column_stack([np.ones_like(z), z, z ** 2, z ** 3])


def follows(size: np.ndarray, variables: dict) -> list[Follows]:
    """Adjusted R² of the per-configuration residual size against each variable, best first.

    Parameters
    ----------
    size : ndarray, shape (M,)
        Mean squared weighted residual of each configuration.
    variables : dict
        From :func:`configuration_variables`.
    """
    m = len(size)
    y = size - size.mean()
    tot = float(y @ y)
    out = []
    for name, (v, unit, is_angle) in variables.items():
        x = smooth_basis(np.asarray(v, float), is_angle)
        k = np.linalg.matrix_rank(x)
        if tot == 0 or m <= k + 1:
            continue
        fit = x @ np.linalg.lstsq(x, size, rcond=None)[0]
        r2 = 1 - float(((size - fit) ** 2).sum()) / tot
        adjusted = 1 - (1 - r2) * (m - 1) / (m - k)
        rho = np.corrcoef(v, size)[0, 1] if np.ptp(v) > 0 else 0.0
        direction = ("grows with" if rho > 0.3 else "falls with" if rho < -0.3
                     else "varies with")
        out.append(Follows(name, unit, float(adjusted), direction))
    return sorted(out, key=lambda f: -f.r2)
