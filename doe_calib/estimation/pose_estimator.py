"""The conventional full-pose estimator (the paper's approach #1), only to compare.

Each configuration's flange pose is reconstructed from its markers (rigid
registration of the tool's marker positions onto the readings); the
residuals are 6-D, ``[Δt (m); λ·Δφ (rad → m)]``, with the normalisation
factor λ in metres per radian. The marker positions are taken as known
(the tool file). Its covariance is propagated exactly from the marker noise
through the reconstruction (a sandwich estimate), not σ²(JᵀJ)⁻¹.
"""
from __future__ import annotations

from dataclasses import replace
from functools import lru_cache

import numpy as np
from scipy.optimize import least_squares

from doe_calib.errors import DataError
from doe_calib.estimation.assembly import finish
from doe_calib.estimation.preparation import prepare
from doe_calib.estimation.registration import register
from doe_calib.model.evaluation import evaluate
from doe_calib.model.pose_model import build_pose_error
from doe_calib.model.rotations import skew_matrix
from doe_calib.model.simulate import simulate
from doe_calib.model.tool import marker_condition


def default_normalisation(tool_positions) -> float:
    """RMS distance of the markers from their centroid (m/rad): the natural λ."""
    c = tool_positions - tool_positions.mean(axis=0)
    return float(np.sqrt(np.mean(np.sum(c ** 2, axis=1))))


_pose_error = lru_cache(maxsize=8)(build_pose_error)
#: Why the pose estimator fixes the marker positions.
KNOWN = "the pose estimator takes the marker positions as known"


def check_tool_fixes_the_pose(markers, source: str = "") -> None:
    """Raise a DataError unless the markers (n, 3), m, can fix a flange pose.

    The pose estimator reconstructs each configuration's full flange pose,
    which takes at least 3 markers not on one line.
    """
    markers = np.asarray(markers, float).reshape(-1, 3)
    if len(markers) < 3 or not np.isfinite(marker_condition(markers)):
        raise DataError(f"the pose estimator reconstructs each flange pose from at least 3 "
                        f"markers not on one line; this tool has {len(markers)} "
                        f"{'marker' if len(markers) == 1 else 'markers on one line'}: use the "
                        f"point estimator (the default, --estimator point), which fits the "
                        f"readings themselves", source or None)


def reconstruct_poses(measurements, markers):
    """Flange pose (R (M,3,3), t (M,3)) of every configuration from its readings.

    ``markers`` (n, 3) are the marker positions in the flange frame, m.
    """
    check_tool_fixes_the_pose(markers, measurements.source)
    m = len(measurements.configurations)
    rot, trans = np.zeros((m, 3, 3)), np.zeros((m, 3))
    for c in range(m):
        rows = measurements.config == c
        if rows.sum() < 3:
            pose = measurements.configurations.pose[c]
            raise DataError(f"pose {pose!r}: {rows.sum()} markers read; the pose estimator needs "
                            f"at least 3 per configuration", measurements.source or None,
                            int(measurements.line[rows][0]) if rows.any() else None)
        rot[c], trans[c] = register(markers[measurements.marker[rows]], measurements.xyz[rows])
    return rot, trans


def identify_pose(model, measurements, params=None, normalisation: float | None = None,
                  max_iterations: int = 200, register: bool = True):
    """Identify from reconstructed flange poses with 6-D residuals.

    Parameters
    ----------
    normalisation : float, optional
        λ in m/rad weighting orientation residuals against position ones;
        default :func:`default_normalisation` of the tool.
    max_iterations : int
        Jacobian evaluations allowed (ten residual evaluations each).
    """
    check_tool_fixes_the_pose(model.tool.position_array, model.tool.source)
    params = model.nominal() if params is None else params
    params, notes, _, absorbed = prepare(model, measurements, params.fixed(["markers"], KNOWN),
                                         register)
    markers, lam, rot, trans, weight = _poses(params, measurements, normalisation)
    free = params.free
    cache = {}

    def evaluate_at(x):
        key = x.tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = _weighted_pose_error(model, params.with_free_values(x).values,
                                              measurements, rot, trans, weight)
        return cache[key]

    sol = least_squares(lambda x: evaluate_at(x)[0], params.free_values(),
                        jac=lambda x: evaluate_at(x)[1][:, free], method="lm",
                        x_scale=params.scales[free], xtol=1e-12, ftol=1e-12, gtol=1e-12,
                        max_nfev=max_iterations * 10)
    params = params.with_free_values(sol.x)
    cov = _sandwich(evaluate_at(sol.x)[1][:, free], weight, rot, markers, measurements)
    convergence = {"converged": bool(sol.status > 0), "iterations": int(sol.njev or sol.nfev),
                   "evaluations": int(sol.nfev), "status": int(sol.status),
                   "message": f"pose estimator (λ = {lam:.4g} m/rad), Levenberg–Marquardt: "
                              f"{sol.message}", "residual_norm2": float(2.0 * sol.cost),
                   "normalisation_m_per_rad": lam}
    return finish(model, measurements, params, "pose", convergence, notes, covariance=cov,
                  absorbed=absorbed, stopped=None if sol.status > 0 else
                  f"pose estimator stopped before converging: {sol.message}")


def predict_pose_covariance(model, params, configurations, sigma: float,
                            normalisation: float | None = None) -> np.ndarray:
    """Predicted covariance (SI) of the pose estimator's free parameters, no data needed.

    Every marker is read at every configuration with noise σ (m); marker
    positions are taken as known, as the pose estimator does.
    """
    params = params.fixed(["markers"], KNOWN)
    meas = simulate(model, params.values, configurations, 0.0)
    meas = replace(meas, sigma=np.full(len(meas), float(sigma)))
    markers, _, rot, trans, weight = _poses(params, meas, normalisation)
    _, jac = _weighted_pose_error(model, params.values, meas, rot, trans, weight)
    return _sandwich(jac[:, params.free], weight, rot, markers, meas)


def _poses(params, measurements, normalisation):
    """The markers (n, 3), λ, the reconstructed flange poses and the 6-D residual weights."""
    markers = params.values[params.index("markers")].reshape(-1, 3)
    lam = default_normalisation(markers) if normalisation is None else float(normalisation)
    rot, trans = reconstruct_poses(measurements, markers)
    weight = np.array([1, 1, 1, lam, lam, lam]) / float(np.median(measurements.sigma))
    return markers, lam, rot, trans, weight


def _weighted_pose_error(model, values, measurements, rot, trans, weight):
    cfg = measurements.configurations
    r_cols = rot.transpose(0, 2, 1).reshape(len(cfg), 9)  # column-major R per configuration
    e, jac = evaluate(_pose_error(model), cfg, values, r_cols, trans)
    return (e[:, :, 0] * weight).ravel(), (jac * weight[None, :, None]).reshape(6 * len(cfg), -1)


def _sandwich(jac, weight, rot, markers, measurements):
    """Covariance of the pose estimate propagated from the marker noise.

    δp̂ = −(JᵀJ)⁻¹Jᵀ W δe and δe_c = G_c δy_c with G_c = (CᵀC)⁻¹Cᵀ the
    linearised pose registration, C rows ``[I, −R[u_j]×]``.
    """
    h = np.linalg.pinv(jac.T @ jac) @ jac.T * np.tile(weight, len(rot))[None, :]
    cov = np.zeros((jac.shape[1], jac.shape[1]))
    for c in range(len(rot)):
        rows = np.flatnonzero(measurements.config == c)
        u = markers[measurements.marker[rows]]
        cmat = np.concatenate([np.hstack([np.eye(3), -rot[c] @ skew_matrix(uj)]) for uj in u])
        g = np.linalg.solve(cmat.T @ cmat, cmat.T)
        a = h[:, 6 * c:6 * c + 6] @ g
        cov += (a * np.repeat(measurements.sigma[rows] ** 2, 3)[None, :]) @ a.T
    return cov
