"""6-DoF probe poses as virtual points with the information of the poses (formats.md §3b).

A probe pose ``(t, R)`` read with σ_pos per coordinate (m) and σ_ang per
axis (rad) becomes points ``t + R·s_k`` at ``s_k = ±d·e_x, ±d·e_y, ±d·e_z``
(σ_axis each) and the origin ``t`` (σ_origin), with

    σ_axis = 2·d·σ_ang,    1/σ_origin² = 1/σ_pos² − 3/(2·d²·σ_ang²),

so that their information about a small probe motion (v, ω) is exactly
``diag(I/σ_pos², I/σ_ang²)``, the pose's own. The points are correlated (all
share the pose's noise) and their residuals lie in the 6-D space of rigid
motions; the weighted sum of squares over them is the pose's Mahalanobis
distance, so the estimate, its covariance and χ² (6 observations per pose,
``Measurements.observed_per_configuration``) are those of the 6-D weighted
fit, to first order in the noise. This needs ``d ≥ √(3/2)·σ_pos/σ_ang``
(:func:`minimum_distance`); at that distance the origin carries nothing.

The points are rigid, so their positions on the flange are fixed (at the
mounting found from the data, :func:`probe_mounting`) and the flange
placement of ``geometry`` carries the mounting error.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from doe_calib.errors import DataError
from doe_calib.io.measurements import GIVEN, Measurements
from doe_calib.model.tool import Tool

#: Virtual point names and their directions in the probe frame.
POINTS = {"O": (0, 0, 0), "X+": (1, 0, 0), "X-": (-1, 0, 0), "Y+": (0, 1, 0),
          "Y-": (0, -1, 0), "Z+": (0, 0, 1), "Z-": (0, 0, -1)}
#: The fixed reason of the virtual points' positions.
RIGID = ("the virtual points of a 6-DoF probe are rigid: their layout is known and the "
         "mounting is carried by the flange placement")


def minimum_distance(sigma: float, angle_sigma: float) -> float:
    """Shortest point distance d (m) at which the points carry the pose's information exactly.

    >>> round(minimum_distance(2e-5, 1e-4), 6)
    0.244949
    """
    return float(np.sqrt(1.5) * sigma / angle_sigma)


def point_sigmas(sigma: float, angle_sigma: float, distance: float) -> tuple[float, float]:
    """(σ_origin, σ_axis), m, of the virtual points at ``distance`` (m); σ_origin inf: no origin.

    Parameters
    ----------
    sigma : float
        Probe position σ per coordinate, m.
    angle_sigma : float
        Probe angle σ per axis, rad.
    distance : float
        Distance d of the axis points from the probe origin, m.
    """
    d_min = minimum_distance(sigma, angle_sigma)
    if distance < d_min * (1 - 1e-9):
        raise DataError(f"virtual points at {1000 * distance:g} mm cannot carry the probe's "
                        f"information: with σ = {1000 * sigma:g} mm and an angular σ of "
                        f"{np.degrees(angle_sigma):g}° they need at least {1000 * d_min:.4g} mm "
                        f"(√1.5·σ/σ_angle; --probe-points-mm)")
    inv = 1.0 / sigma ** 2 - 1.5 / (distance * angle_sigma) ** 2
    return (float(1.0 / np.sqrt(inv)) if inv > 1e-12 / sigma ** 2 else float("inf"),
            float(2.0 * distance * angle_sigma))


def probe_mounting(robot, readings) -> tuple[np.ndarray, np.ndarray]:
    """The probe frame in the flange frame, (R (3, 3), t (3,) m), from the nominal robot.

    Hand–eye from the readings: the probe's turns between poses are the
    flange's turns seen in the probe frame (``b_i = Rᵀ a_i`` for the rotation
    vectors relative to the first pose), then the translations by linear
    least squares. A start value: the fit refines it through the flange placement.
    """
    rf, tf = robot.flange_poses(readings.configurations.q)
    rp, tp = readings.rotation, readings.position
    a = Rotation.from_matrix(np.einsum("ji,mjk->mik", rf[0], rf)).as_rotvec()
    b = Rotation.from_matrix(np.einsum("ji,mjk->mik", rp[0], rp)).as_rotvec()
    if np.linalg.matrix_rank(a[np.linalg.norm(a, axis=1) > 1e-3], tol=1e-3) < 2:
        raise DataError("the probe poses turn the flange about one axis only: its mounting "
                        "cannot be found; measure poses that turn the wrist about two axes",
                        readings.source or None)
    r_fp = Rotation.align_vectors(a, b)[0].as_matrix()
    r_tb = Rotation.from_matrix(rp @ r_fp.T @ rf.transpose(0, 2, 1)).mean().as_matrix()
    m = len(readings)
    lhs = np.concatenate([np.tile(np.eye(3), (m, 1, 1)), r_tb @ rf], axis=2).reshape(3 * m, 6)
    rhs = (tp - tf @ r_tb.T).reshape(-1)
    sol = np.linalg.lstsq(lhs, rhs, rcond=None)[0]
    return r_fp, sol[3:]


def probe_points(robot, readings, sigma: float, angle_sigma: float,
                 distance: float | None = None) -> tuple[Tool, Measurements]:
    """The virtual tool and the virtual readings of a 6-DoF probe campaign.

    Parameters
    ----------
    robot : Robot
    readings : ProbeReadings
        From :func:`~doe_calib.io.probe_file.read_probe`.
    sigma : float
        Position σ per coordinate, m.
    angle_sigma : float
        Angle σ per axis, rad.
    distance : float, optional
        Distance of the axis points from the probe origin, m; default twice
        :func:`minimum_distance`.

    Returns
    -------
    tool : Tool
        The points ``O, X+ … Z-`` on the flange at the estimated mounting.
    measurements : Measurements
        Their positions at every pose with σ from :func:`point_sigmas`; 6
        observations per pose. Fit with ``RIGID`` points (see :func:`probe_parameters`).

    Examples
    --------
    >>> tool, meas = probe_points(robot, read_probe("p.csv", robot, "rpy"),
    ...                           2e-5, np.radians(0.01))          # doctest: +SKIP
    """
    if not (sigma > 0 and angle_sigma > 0):
        raise DataError("a 6-DoF probe needs its position σ and its angular σ, both positive "
                        "(--sigma MM, --angle-sigma-deg DEG)", readings.source or None)
    distance = 2.0 * minimum_distance(sigma, angle_sigma) if distance is None else distance
    s_origin, s_axis = point_sigmas(sigma, angle_sigma, distance)
    names = [n for n in POINTS if n != "O" or np.isfinite(s_origin)]
    s = distance * np.array([POINTS[n] for n in names], float)
    r_fp, t_fp = probe_mounting(robot, readings)
    tool = Tool.from_markers({n: list(1000.0 * (t_fp + r_fp @ p)) for n, p in zip(names, s)},
                             robot.flange)
    m, k = len(readings), len(names)
    xyz = readings.position[:, None, :] + np.einsum("mij,kj->mki", readings.rotation, s)
    sig = np.array([s_origin if n == "O" else s_axis for n in names])
    meas = Measurements(readings.configurations, np.repeat(np.arange(m), k),
                        np.tile(np.arange(k), m), xyz.reshape(-1, 3), np.tile(sig, m),
                        np.repeat(readings.line, k), readings.source,
                        warnings=readings.warnings, session=readings.session,
                        sigma_source=GIVEN, observed_per_configuration=6)
    return tool, meas


def probe_parameters(model):
    """The model's nominal parameters with the virtual points fixed (:data:`RIGID`)."""
    return model.nominal().fixed(["markers"], RIGID)
