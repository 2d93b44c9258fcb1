"""Identification from all 3·m·n marker coordinates (the ``point`` estimator) and
what every estimator shares: start values, rank analysis, result assembly.

The weighted residuals and their Jacobian (:mod:`doe_calib.weighted`) are
taken a block of configurations at a time and kept only as their QR factor
(:mod:`doe_calib.least_squares`), so memory does not grow with the number of
readings.
"""
from __future__ import annotations

import logging
import warnings
from dataclasses import replace

import numpy as np

from . import plausibility
from .errors import (ConditioningWarning, ConvergenceWarning, DataError,
                     IdentifiabilityWarning, PlausibilityWarning, SolverError)
from .evaluation import marker_positions
from .identifiability import analyse
from .least_squares import levenberg_marquardt
from .measurement import for_workload
from .registration import register
from .results import IdentificationResult
from .rotations import matrix_to_rotation_vector
from .weighted import reduce_jacobian, residual_norm2

log = logging.getLogger(__name__)

ESTIMATORS = ("point", "two-step", "pose")
_COND_WARN = 1e6
#: Passes over every configuration a typical fit makes (start, Jacobians, trial
#: steps, result): what :func:`~doe_calib.measurement.for_workload` is told.
_PASSES = 10


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
    red = reduce_jacobian(model, measurements, params.values)
    ident = analyse(red.r_factor, params, tol=tol)  # RᵀR = JᵀJ: same columns' geometry
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
    sq, d = np.sum(e ** 2, axis=1), np.linalg.norm(e, axis=1)

    def stats(groups, names):
        n = np.bincount(groups, minlength=len(names))
        ss = np.bincount(groups, sq, minlength=len(names))
        worst = np.full(len(names), -np.inf)
        np.maximum.at(worst, groups, d)
        return {name: {"rms_mm": float(np.sqrt(ss[k] / (3 * n[k]))),
                       "max_3d_mm": float(worst[k]), "n": int(n[k])}
                for k, name in enumerate(names) if n[k]}

    out = stats(np.zeros(len(d), int), ["all"])["all"]
    out["per_marker"] = stats(measurements.marker, list(model.tool.names))
    pose_names, pose_of_config = np.unique(np.asarray(measurements.configurations.pose, object),
                                           return_inverse=True)
    first = {}  # poses in order of first reading, as in the file
    for p in np.asarray(pose_names)[pose_of_config[measurements.config]]:
        first.setdefault(p, None)
    per_pose = stats(pose_of_config[measurements.config], list(pose_names))
    out["per_pose"] = {p: per_pose[p] for p in first}
    return out


def finish(model, measurements, params, estimator, convergence, notes, covariance=None,
           norm2=None):
    """Assemble the result: covariance σ²(BᵀWB)⁻¹, σ̂, residual statistics.

    ``covariance`` (of the free parameters, SI) and ``norm2`` (‖r‖² at
    ``params``) are computed here, a block of readings at a time, unless given.
    """
    n_free = int(params.free.sum())
    if covariance is None or norm2 is None:
        red = reduce_jacobian(model, measurements, params.values, params.free)
        covariance = _covariance(red.r_factor) if covariance is None else covariance
        norm2 = red.norm2 if norm2 is None else norm2
    n_obs = 3 * len(measurements)
    dof = n_obs - n_free
    ratio = float(np.sqrt(norm2 / dof)) if dof > 0 else float("nan")
    sigma_mm = float(np.median(measurements.sigma) * 1000.0)
    estimated = bool(measurements.sigma_estimated and np.isfinite(ratio))
    if estimated:  # σ unknown: σ̂ becomes σ and scales the covariance (statsmodels' scale)
        covariance, sigma_mm, ratio = covariance * ratio ** 2, sigma_mm * ratio, 1.0
        notes = [f"σ estimated from the residuals: {sigma_mm:.3g} mm"] + list(notes)
    return IdentificationResult(
        model.robot, model.tool, model.spec, estimator, params, covariance, ratio,
        residual_statistics(model, measurements, params.values), convergence, n_obs,
        sigma_mm, tuple(notes), estimated)


def _covariance(r_factor, scale=None) -> np.ndarray:
    """(JᵀJ)⁺ from R (RᵀR = JᵀJ) of the Jacobian scaled by ``scale``, in unscaled units."""
    r_inv = np.linalg.pinv(r_factor)
    cov = r_inv @ r_inv.T
    return cov if scale is None else cov * np.outer(scale, scale)


def identify_point(model, measurements, params=None, max_iterations: int = 200,
                   register: bool = True, progress=None) -> IdentificationResult:
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
    progress : callable(stage, note), optional
        Told of each iteration (weighted RMS of the residuals).
    """
    params, notes = prepare(model, measurements, params, register)
    free = params.free
    scale = params.scales[free]
    n_obs = 3 * len(measurements)

    def values(x):
        return params.with_free_values(x).values

    sol = levenberg_marquardt(
        lambda x: residual_norm2(model, measurements, values(x)),
        lambda x: reduce_jacobian(model, measurements, values(x), free, scale),
        params.free_values(), scale, max_iterations=max_iterations,
        progress=None if progress is None else lambda k, f: progress(
            "Levenberg–Marquardt", f"iteration {k}, weighted RMS {np.sqrt(f / n_obs):.4g}"))
    if not np.all(np.isfinite(sol.x)):
        raise SolverError("the identification diverged (non-finite parameters); check the "
                          "tool file and the units of the measurement file")
    if not sol.converged:
        msg = f"Levenberg–Marquardt stopped before converging: {sol.message}"
        warnings.warn(msg, ConvergenceWarning, stacklevel=2)
        notes.append(msg)
    log.info("point estimator: %d Jacobian and %d residual passes, status %d", sol.iterations,
             sol.evaluations, sol.status)
    convergence = {"converged": sol.converged, "iterations": sol.iterations,
                   "evaluations": sol.evaluations, "status": sol.status,
                   "message": f"Levenberg–Marquardt: {sol.message}", "residual_norm2": sol.norm2}
    return finish(model, measurements, params.with_free_values(sol.x), "point", convergence,
                  notes, _covariance(sol.reduction.r_factor, scale), sol.norm2)


def identify(model, measurements, params=None, estimator: str = "point", progress=None,
             **options):
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
    progress : callable(stage, note), optional
        Told of long steps (compiling the model, each iteration of ``point``).

    Returns
    -------
    IdentificationResult
        Its ``warnings`` end with the plausibility findings (σ̂/σ far from 1,
        units, placement errors as large as a link, collinear markers). When
        ``measurements.sigma_estimated``, σ is estimated from the residuals:
        ``sigma_mm`` is σ̂, the covariance is scaled to it, and the result says so.
    """
    model = for_workload(model, _PASSES * len(measurements.configurations), progress)
    if estimator == "point":
        result = identify_point(model, measurements, params, progress=progress, **options)
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
