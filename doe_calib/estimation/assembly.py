"""What every estimator does last: the covariance σ²(BᵀWB)⁻¹, σ̂ and the residual
statistics, assembled into an :class:`~doe_calib.estimation.result.IdentificationResult`.
"""
from __future__ import annotations

import warnings

import numpy as np

from doe_calib.errors import ConvergenceWarning
from doe_calib.estimation.covariance import covariance_from_r_factor
from doe_calib.estimation.observation_count import reading_counts
from doe_calib.estimation.measured_region import joint_range
from doe_calib.estimation.result import IdentificationResult
from doe_calib.estimation.planes import plane_note
from doe_calib.estimation.sockets import socket_note
from doe_calib.estimation.weighted_residuals import marker_residuals, reduce_jacobian

#: The note a fit that estimates σ leads its notes with (its σ̂ follows, mm).
SIGMA_ESTIMATED = "σ estimated from the residuals"


def residual_statistics(model, measurements, values) -> dict:
    """Residual RMS (per coordinate) and max 3-D error, overall, per marker and per pose, mm;
    ``counts``: the readings by kind (:func:`reading_counts`).

    A plane touch or a ballbar length is one coordinate, its residual (along the plane's
    normal, along the bar) its whole error; any other reading is three.
    """
    e = marker_residuals(model, measurements, values) * 1000.0
    sq, d = np.sum(e ** 2, axis=1), np.linalg.norm(e, axis=1)
    coordinates = np.where(measurements.touch | measurements.ballbar, 1, 3)

    def stats(groups, names):
        n = np.bincount(groups, minlength=len(names))
        ss = np.bincount(groups, sq, minlength=len(names))
        read = np.bincount(groups, coordinates, minlength=len(names))
        worst = np.full(len(names), -np.inf)
        np.maximum.at(worst, groups, d)
        seen = n > 0  # one vectorised pass, then plain floats (same values as one by one)
        rms = np.sqrt(ss[seen] / read[seen])
        return {name: {"rms_mm": r, "max_3d_mm": w, "n": c} for name, r, w, c in
                zip(np.asarray(names, object)[seen], rms.tolist(), worst[seen].tolist(),
                    n[seen].tolist())}

    out = stats(np.zeros(len(d), int), ["all"])["all"]
    out["per_marker"] = stats(measurements.marker, list(model.tool.names))
    pose_names, pose_of_config = np.unique(np.asarray(measurements.configurations.pose, object),
                                           return_inverse=True)
    per_pose = stats(pose_of_config[measurements.config], list(pose_names))
    # poses in order of first reading, as in the file
    first = dict.fromkeys(np.asarray(pose_names)[pose_of_config[measurements.config]])
    out["per_pose"] = {p: per_pose[p] for p in first}
    out["counts"] = reading_counts(measurements)
    return out


def finish(model, measurements, params, estimator, convergence, notes, covariance=None,
           norm2=None, absorbed=None, stopped=None):
    """Assemble the result: covariance σ²(BᵀWB)⁻¹, σ̂, residual statistics.

    ``stopped``: why the estimator stopped before converging, in words; it is issued as a
    :class:`~doe_calib.errors.ConvergenceWarning` (to the estimator's caller) and noted.
    ``covariance`` (of the free parameters, SI) and ``norm2`` (‖r‖² at
    ``params``) are computed here, a block of readings at a time, unless given.
    ``absorbed``: what each free parameter absorbs of those fixed as not separable
    (:attr:`~doe_calib.estimation.identifiability.Identifiability.absorbed`).
    """
    if stopped:
        warnings.warn(stopped, ConvergenceWarning, stacklevel=3)
        notes = list(notes) + [stopped]
    n_free = int(params.free.sum())
    if covariance is None or norm2 is None:
        red = reduce_jacobian(model, measurements, params.values, params.free)
        covariance = covariance_from_r_factor(red.r_factor) if covariance is None else covariance
        norm2 = red.norm2 if norm2 is None else norm2
    n_obs = measurements.n_coordinates
    dof = n_obs - n_free
    ratio = float(np.sqrt(norm2 / dof)) if dof > 0 else float("nan")
    sigma_mm = float(np.median(measurements.sigma) * 1000.0)
    estimated = bool(measurements.sigma_estimated and np.isfinite(ratio))
    scale = ratio ** 2 if estimated else 1.0
    if estimated:  # σ unknown: σ̂ becomes σ and scales the covariance (statsmodels' scale)
        covariance, sigma_mm, ratio = covariance * ratio ** 2, sigma_mm * ratio, 1.0
        notes = [f"{SIGMA_ESTIMATED}: {sigma_mm:.3g} mm"] + list(notes)
    located = [note(model, measurements, params, covariance, scale)
               for note in (socket_note, plane_note)]
    notes = list(notes) + [n for n in located if n]
    return IdentificationResult(
        model.robot, model.tool, model.spec, estimator, params, covariance, ratio,
        residual_statistics(model, measurements, params.values), convergence, n_obs,
        sigma_mm, tuple(notes), estimated,
        "estimated" if estimated else measurements.sigma_source,
        {e.name: str(e.source) for e in model.effects if getattr(e, "source", "")},  # user effects
        dict(absorbed or {}), joint_range=joint_range(measurements))
