"""Identification from all 3·m·n marker coordinates (the ``point`` estimator) and
what every estimator shares: weighted residuals, rank analysis, result assembly.

The weighted residual of reading k (configuration c, marker j) is
``r_k = (y_k − x_cj(p)) / σ_k``; its Jacobian is ``−B_cj / σ_k`` with ``B`` the
model's observation matrix (CasADi, never finite differences).
"""
from __future__ import annotations

import logging
import warnings
from dataclasses import replace

import numpy as np
from scipy.optimize import least_squares

from . import plausibility
from .errors import (ConditioningWarning, ConvergenceWarning, DataError,
                     IdentifiabilityWarning, PlausibilityWarning, SolverError)
from .evaluation import marker_positions, observation_matrix
from .identifiability import analyse
from .registration import register
from .results import IdentificationResult
from .rotations import matrix_to_rotation_vector

log = logging.getLogger(__name__)

ESTIMATORS = ("point", "two-step", "pose")
_COND_WARN = 1e6


def weighted_residual(model, measurements, values, jacobian: bool = True):
    """Weighted residuals r (3K,) and, if asked, ∂r/∂p (3K, P) for all P parameters."""
    cfg = measurements.configurations
    if jacobian:
        x, b = observation_matrix(model, values, cfg)
    else:
        x, b = marker_positions(model, values, cfg), None
    c, j, s = measurements.config, measurements.marker, measurements.sigma[:, None]
    r = ((measurements.xyz - x[c, j]) / s).ravel()
    if not jacobian:
        return r, None
    jac = -(b[c, j] / s[:, :, None]).reshape(3 * len(measurements), -1)
    return r, jac


def register_base(model, measurements, params):
    """Start values of the base pose from a point-set registration of all readings.

    The markers are placed with the current robot parameters (base at the
    identity), then rotated and shifted onto the readings: any tracker
    placement and any angle is found, no small-angle assumption.
    """
    base = params.index("base")
    v = params.values.copy()
    v[base] = 0.0
    x = marker_positions(model, v, measurements.configurations)
    robot_pts = x[measurements.config, measurements.marker]
    rot, t = register(robot_pts, measurements.xyz, 1.0 / measurements.sigma ** 2)
    v[base[:3]] = t
    v[base[3:]] = matrix_to_rotation_vector(rot)
    return params.with_values(v)


def _fixed_sentence(params, names) -> str:
    """One sentence: how many parameters were fixed as not separable, counted by block."""
    blocks = [params.parameters[i].block for i in params.index(names)]
    by_block = ", ".join(f"{blocks.count(b)} {b}" for b in dict.fromkeys(blocks))
    return (f"{len(names)} parameters fixed as not separable by these data ({by_block}); "
            f"the reason for each is in the result (the result JSON's \"fixed\" list; "
            f"doe-calib identify --verbose prints them)")


def fix_unidentifiable(model, measurements, params, tol: float = 1e-7):
    """Fix (at their current values) the free parameters the data cannot separate.

    Returns the new parameter set and the warnings issued, in words.
    """
    _, jac = weighted_residual(model, measurements, params.values)
    ident = analyse(jac, params, tol=tol)
    notes = []
    if ident.dependent:
        names = [n for n, _ in ident.dependent]
        for name, why in ident.dependent:
            params = params.fixed([name], why + "; fixed at its current value")
        warnings.warn(_fixed_sentence(params, names), IdentifiabilityWarning, stacklevel=3)
        notes.append(f"{len(names)} parameters fixed as not identifiable (see the fixed list)")
    if ident.condition_number > _COND_WARN:
        msg = (f"the observation matrix is poorly conditioned (condition number "
               f"{ident.condition_number:.2g}); the weakest combination involves "
               f"{', '.join(ident.weakest)}: these will have large standard deviations")
        warnings.warn(msg, ConditioningWarning, stacklevel=3)
        notes.append(msg)
    return params, notes


def check_counts(measurements, params):
    """Raise a DataError when there are fewer observations than unknowns."""
    n_free = int(params.free.sum())
    if measurements.n_coordinates < n_free:
        raise DataError(f"{measurements.n_coordinates} observed coordinates for {n_free} unknown "
                        f"parameters: measure more poses or markers, or use a smaller model",
                        measurements.source or "<measurements>")


def prepare(model, measurements, params=None, register: bool = True):
    """Common start of every estimator: start values, base registration, rank analysis."""
    params = model.nominal() if params is None else params
    if len(measurements) == 0:
        raise DataError("no readings to identify from", measurements.source or "<measurements>")
    if register and params.free[params.index("base")].all():
        params = register_base(model, measurements, params)
    check_counts(measurements, params)
    return fix_unidentifiable(model, measurements, params)


def residual_statistics(model, measurements, values) -> dict:
    """Residual RMS (per coordinate) and max 3-D error, overall, per marker and per pose, mm."""
    x = marker_positions(model, values, measurements.configurations)
    e = (measurements.xyz - x[measurements.config, measurements.marker]) * 1000.0
    d = np.linalg.norm(e, axis=1)

    def stats(mask):
        return {"rms_mm": float(np.sqrt(np.mean(e[mask] ** 2))), "max_3d_mm": float(d[mask].max()),
                "n": int(mask.sum())}

    names = model.tool.names
    poses = measurements.configurations.pose
    pose_of_row = np.array([poses[c] for c in measurements.config])
    out = stats(np.ones(len(d), bool))
    out["per_marker"] = {names[j]: stats(measurements.marker == j)
                         for j in np.unique(measurements.marker)}
    out["per_pose"] = {p: stats(pose_of_row == p) for p in dict.fromkeys(pose_of_row)}
    return out


def finish(model, measurements, params, estimator, convergence, notes, covariance=None):
    """Assemble the result: covariance σ²(BᵀWB)⁻¹, σ̂, residual statistics."""
    r, jac = weighted_residual(model, measurements, params.values)
    jf = jac[:, params.free]
    n_free = jf.shape[1]
    if covariance is None:
        covariance = np.linalg.pinv(jf.T @ jf)
    dof = len(r) - n_free
    ratio = float(np.sqrt(r @ r / dof)) if dof > 0 else float("nan")
    sigma_mm = float(np.median(measurements.sigma) * 1000.0)
    estimated = bool(measurements.sigma_estimated and np.isfinite(ratio))
    if estimated:  # σ unknown: σ̂ becomes σ and scales the covariance (statsmodels' scale)
        covariance, sigma_mm, ratio = covariance * ratio ** 2, sigma_mm * ratio, 1.0
        notes = [f"σ estimated from the residuals: {sigma_mm:.3g} mm"] + list(notes)
    return IdentificationResult(
        model.robot, model.tool, model.spec, estimator, params, covariance, ratio,
        residual_statistics(model, measurements, params.values), convergence, len(r),
        sigma_mm, tuple(notes), estimated)


def identify_point(model, measurements, params=None, max_iterations: int = 200,
                   register: bool = True) -> IdentificationResult:
    """Levenberg–Marquardt on all marker coordinates (the paper's approach #2).

    Parameters
    ----------
    model : Model
    measurements : Measurements
    params : ParameterSet, optional
        Start values and free/fixed flags; default nominal, all free.
    max_iterations : int
        Jacobian evaluations allowed.
    register : bool
        Start the base pose from a point-set registration.
    """
    params, notes = prepare(model, measurements, params, register)
    free = params.free
    scale = params.scales[free]
    cache = {}

    def evaluate(x, jacobian: bool):
        """(r, J) at x; J only when asked (trial steps need the residual alone)."""
        key = x.tobytes()
        hit = cache.get(key)
        if hit is None or (jacobian and hit[1] is None):
            cache.clear()
            cache[key] = hit = weighted_residual(model, measurements,
                                                 params.with_free_values(x).values, jacobian)
        return hit

    sol = least_squares(lambda x: evaluate(x, False)[0], params.free_values(),
                        jac=lambda x: evaluate(x, True)[1][:, free], method="lm", x_scale=scale,
                        xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=max_iterations * 10)
    if not np.all(np.isfinite(sol.x)):
        raise SolverError("the identification diverged (non-finite parameters); check the "
                          "tool file and the units of the measurement file")
    converged = sol.status > 0
    if not converged:
        msg = f"Levenberg–Marquardt stopped before converging: {sol.message}"
        warnings.warn(msg, ConvergenceWarning, stacklevel=2)
        notes.append(msg)
    log.info("point estimator: %d evaluations, status %d", sol.nfev, sol.status)
    convergence = {"converged": bool(converged), "iterations": int(sol.njev or sol.nfev),
                   "evaluations": int(sol.nfev), "status": int(sol.status),
                   "message": f"Levenberg–Marquardt: {sol.message}",
                   "residual_norm2": float(2.0 * sol.cost)}
    return finish(model, measurements, params.with_free_values(sol.x), "point", convergence,
                  notes)


def identify(model, measurements, params=None, estimator: str = "point", **options):
    """Identify the model's parameters from marker readings.

    Parameters
    ----------
    model : Model
        From :func:`~doe_calib.measurement.build_model`.
    measurements : Measurements
        Readings (SI) with their σ.
    params : ParameterSet, optional
        Start values and which parameters are free (fix any by name or block
        with ``ParameterSet.fixed``); default: nominal, all free.
    estimator : {"point", "two-step", "pose"}
        ``point``: all marker coordinates, Levenberg–Marquardt (default).
        ``two-step``: the paper's alternation of base+markers and robot
        parameters. ``pose``: full poses reconstructed from the markers, only
        for comparison (``normalisation`` option, m/rad).

    Returns
    -------
    IdentificationResult
        Its ``warnings`` end with the plausibility findings (σ̂/σ far from 1,
        units, placement errors as large as a link, collinear markers). When
        ``measurements.sigma_estimated``, σ is estimated from the residuals:
        ``sigma_mm`` is σ̂, the covariance is scaled to it, and the result says so.
    """
    if estimator == "point":
        result = identify_point(model, measurements, params, **options)
    elif estimator == "two-step":
        from .two_step import identify_two_step
        result = identify_two_step(model, measurements, params, **options)
    elif estimator == "pose":
        from .pose_estimator import identify_pose
        result = identify_pose(model, measurements, params, **options)
    else:
        raise ValueError(f"unknown estimator {estimator!r}; choose one of "
                         f"{', '.join(ESTIMATORS)}")
    return with_plausibility(model, measurements, result)


def with_plausibility(model, measurements, result):
    """``result`` with the :mod:`~doe_calib.plausibility` findings added to its warnings,
    each also issued as a :class:`~doe_calib.errors.PlausibilityWarning`."""
    findings = plausibility.check(model, measurements, result)
    for f in findings:
        warnings.warn(f, PlausibilityWarning, stacklevel=3)
    return replace(result, warnings=result.warnings + findings) if findings else result


def identify_quietly(model, measurements, params=None, **options):
    """:func:`identify` for fits run many times (cross-validation, diagnosis, refinement).

    Identifiability, conditioning and convergence trouble is not issued as
    warnings: it stays, in words, in the result's ``warnings``.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return identify(model, measurements, params, **options)
