"""The ``point`` estimator: Levenberg–Marquardt on all 3·m·n marker coordinates.

The weighted residuals and their Jacobian
(:mod:`doe_calib.estimation.weighted_residuals`) are taken a block of
configurations at a time and kept only as their QR factor
(:mod:`doe_calib.estimation.least_squares`), so memory does not grow with the
number of readings.
"""
from __future__ import annotations

import logging

from doe_calib.estimation.assembly import finish
from doe_calib.estimation.covariance import covariance_from_r_factor
from doe_calib.estimation.point_fit import point_fit
from doe_calib.estimation.preparation import prepare
from doe_calib.estimation.result import IdentificationResult

log = logging.getLogger(__name__)

#: Passes over every configuration a typical fit makes (start, Jacobians, trial
#: steps, result): what :func:`~doe_calib.model.marker_model.for_workload` is told.
FIT_PASSES = 10


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
    progress : callable, optional
        ``progress(done, total, note)`` after each iteration: iterations done, the
        limit, the weighted RMS of the residuals.
    """
    params, notes, start, absorbed = prepare(model, measurements, params, register)
    sol = point_fit(model, measurements, params, max_iterations, progress, start)
    scale = params.scales[params.free]
    log.info("point estimator: %d Jacobian and %d residual passes, status %d", sol.iterations,
             sol.evaluations, sol.status)
    convergence = {"converged": sol.converged, "iterations": sol.iterations,
                   "evaluations": sol.evaluations, "status": sol.status,
                   "message": f"Levenberg–Marquardt: {sol.message}", "residual_norm2": sol.norm2}
    return finish(model, measurements, params.with_free_values(sol.x), "point", convergence,
                  notes, covariance_from_r_factor(sol.reduction.r_factor, scale), sol.norm2,
                  absorbed, None if sol.converged else
                  f"Levenberg–Marquardt stopped before converging: {sol.message}")
