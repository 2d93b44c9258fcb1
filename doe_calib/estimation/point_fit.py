"""One Levenberg–Marquardt fit of the free parameters on all marker coordinates.

The numerical step shared by the ``point`` estimator
(:mod:`doe_calib.estimation.point_estimator`, which adds the rank analysis and
the result) and the re-registration of a new session
(:mod:`doe_calib.estimation.session`, which frees only the tracker frame and
the tool mounting).
"""
from __future__ import annotations

import numpy as np

from doe_calib.errors import SolverError
from doe_calib.estimation.least_squares import levenberg_marquardt, restrict
from doe_calib.estimation.weighted_residuals import reduce_jacobian, residual_norm2


def point_fit(model, measurements, params, max_iterations: int = 200, progress=None,
              start=None):
    """Levenberg–Marquardt on the free parameters of ``params``, the others held.

    Parameters
    ----------
    model : Model
    measurements : Measurements
    params : ParameterSet
        Start values (SI) and which parameters are free.
    max_iterations : int
        Jacobian evaluations allowed.
    progress : callable, optional
        ``progress(done, total, note)`` after each iteration: iterations done, the
        limit, the weighted RMS of the residuals.
    start : Reduction, optional
        Of ``[J | r]`` for all parameters, unscaled, at ``params.values`` (the rank
        analysis' own, :func:`~doe_calib.estimation.preparation.prepare`): the first
        Jacobian pass is then taken from it instead of the data.

    Returns
    -------
    Solution
        :class:`~doe_calib.estimation.least_squares.Solution`; ``x`` holds the
        free values (SI).

    Raises
    ------
    SolverError
        The fit diverged (non-finite parameters).
    """
    free = params.free
    scale = params.scales[free]
    n_obs = measurements.n_coordinates

    def values(x):
        return params.with_free_values(x).values

    sol = levenberg_marquardt(
        lambda x: residual_norm2(model, measurements, values(x)),
        lambda x: reduce_jacobian(model, measurements, values(x), free, scale),
        params.free_values(), scale, max_iterations=max_iterations,
        first=None if start is None else restrict(start, np.flatnonzero(free), scale),
        progress=None if progress is None else lambda k, f: progress(
            k, max_iterations, f"Levenberg–Marquardt: weighted RMS {np.sqrt(f / n_obs):.4g}"))
    if not np.all(np.isfinite(sol.x)):
        raise SolverError("the identification diverged (non-finite parameters); check the "
                          "tool file and the units of the measurement file")
    return sol
