"""Where σ comes from: the one policy for the tracker's σ per coordinate.

A reading's σ has one of four sources (:data:`SIGMA_SOURCES`):

``"given"``
    an option or keyword (``--sigma`` in mm, ``sigma=`` in m) for every
    reading without a σ of its own;
``"per reading"``
    the measurement file's ``sigma`` column;
``"repeated readings"``
    neither, and poses read more than once: σ is their pooled spread
    (:mod:`~doe_calib.estimation.repeatability`), which holds no model error;
``"estimated"``
    none of these: σ is the σ̂ of the starting model's fit to the readings.

A σ given is the σ used: repeated readings never replace it, they are
reported beside it (:attr:`SettledSigma.repeated`).

The readers return each reading's σ, or NaN where none is given (the readings
are then marked ``sigma_estimated``). :func:`resolve_sigma` is the one place
that decides: identify, diagnose, refine and the commands built on them call
it first, so the Python API and the command line test a model against the
same σ. ``identify`` leaves the estimate to its own fit (``in_fit``): its σ̂
*is* the starting model's, and its covariance is scaled to it; the fit weighs
the readings with a provisional σ meanwhile (:func:`provisional`).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, replace

import numpy as np

from doe_calib.errors import DataError, DoeCalibWarning, OptionError
from doe_calib.estimation.point_estimator import FIT_PASSES, identify_point
from doe_calib.estimation.repeatability import Repeatability, repeatability
from doe_calib.io.measurements import (
    ESTIMATED,
    GIVEN,
    PER_READING,
    REPEATED,
    Measurements,
    provisional,
)
from doe_calib.model.marker_model import for_workload


@dataclass(frozen=True, eq=False)
class SettledSigma:
    """Readings whose σ is settled, and how.

    Attributes
    ----------
    measurements : Measurements
        The readings with their σ (m); ``sigma_estimated`` is False unless
        ``in_fit`` left the estimate to the caller's fit.
    source : str
        One of :data:`SIGMA_SOURCES`.
    sigma_mm : float
        The median σ of the readings, mm (NaN while the caller's fit estimates it).
    words : str
        How σ was decided, for a message (``σ given: 0.02 mm``).
    repeated : Repeatability or None
        σ of the readings repeated in one pose, whatever the source (None when too
        few are): the σ used when none is given, else reported beside it.
    """

    measurements: Measurements
    source: str
    sigma_mm: float
    words: str
    repeated: Repeatability | None = None


def with_sigma(measurements, sigma: float, source: str = GIVEN) -> Measurements:
    """``measurements`` with every reading's σ set to ``sigma`` (m), from ``source``
    (one of :data:`~doe_calib.io.measurements.SIGMA_SOURCES`).

    Raises
    ------
    OptionError
        When ``sigma`` is not a positive finite number.
    """
    if not (np.isfinite(sigma) and sigma > 0):
        raise OptionError(f"σ must be a positive number of metres, got {sigma!r}")
    return replace(measurements, sigma=np.full(len(measurements), float(sigma)),
                   sigma_source=source, sigma_estimated=False)


def resolve_sigma(model, measurements, sigma: float | None = None, params=None, fit=None,
                  in_fit: bool = False) -> SettledSigma:
    """Settle the σ of ``measurements``: given, per reading, from repeated readings, or estimated.

    Parameters
    ----------
    model : Model
        The starting model, whose fit estimates σ when none is known.
    measurements : Measurements
        Readings in SI, as read (``sigma_estimated`` when no σ came with them).
    sigma : float, optional
        σ per coordinate, m, for every reading (source ``"given"``); it
        replaces whatever σ the readings carry.
    params : ParameterSet, optional
        Start values and free parameters of the starting fit (default nominal).
    fit : IdentificationResult, optional
        The starting model's fit to these readings, when at hand: its σ̂ is the
        estimate (no second fit).
    in_fit : bool
        The caller's own fit estimates σ (``identify``): readings without σ
        are returned as they are, still ``sigma_estimated`` (repeated readings or not).

    Returns
    -------
    SettledSigma

    Raises
    ------
    DataError
        When σ must be estimated and the readings cannot give it (no more
        coordinates than free parameters).

    Examples
    --------
    >>> from doe_calib import Robot, Tool, build_model, examples, simulate
    >>> from doe_calib.model.simulate import random_configurations
    >>> from doe_calib.io.measurements import Configurations
    >>> model = build_model(Robot.from_urdf(examples.ROBOT_URDF),
    ...                     Tool.from_yaml(examples.TOOL_YAML), "joint_offset")
    >>> cfg = Configurations.from_arrays(random_configurations(model.robot, 20))
    >>> meas = simulate(model, model.nominal().values, cfg, 2e-5)
    >>> resolve_sigma(model, meas, sigma=3e-5).words
    'σ given: 0.03 mm'
    """
    rep = repeatability(measurements)
    if sigma is not None:
        settled = with_sigma(measurements, sigma)
        return SettledSigma(settled, GIVEN, sigma * 1000.0, f"σ given: {sigma * 1000.0:.3g} mm",
                            rep)
    if not measurements.sigma_estimated:
        median = float(np.median(measurements.sigma) * 1000.0) if len(measurements) else np.nan
        words = {GIVEN: f"σ given: {median:.3g} mm",
                 PER_READING: f"σ per reading (the file's sigma column): median "
                              f"{median:.3g} mm",
                 ESTIMATED: f"σ estimated from the residuals of the starting model, "
                            f"{median:.3g} mm",
                 REPEATED: f"σ not given: from repeated readings, {median:.3g} mm"}
        return SettledSigma(measurements, measurements.sigma_source, median,
                            words[measurements.sigma_source], rep)
    if in_fit:
        return SettledSigma(measurements, ESTIMATED, float("nan"),
                            "σ not given: estimated from the residuals of this fit", rep)
    if rep is not None:
        return SettledSigma(with_sigma(measurements, rep.sigma_mm / 1000.0, REPEATED), REPEATED,
                            rep.sigma_mm, f"σ not given: {rep.summary()}", rep)
    if fit is None or not fit.sigma_estimated:
        fit = _starting_fit(model, measurements, params)
    if not (fit.sigma_estimated and np.isfinite(fit.sigma_mm) and fit.sigma_mm > 0):
        raise DataError(f"σ is not given and cannot be estimated: {3 * len(measurements)} "
                        f"coordinates for {int(fit.parameters.free.sum())} free parameters; give "
                        f"σ (a sigma column, --sigma or sigma=)", measurements.source or None)
    return SettledSigma(with_sigma(measurements, fit.sigma_mm / 1000.0, ESTIMATED), ESTIMATED,
                        fit.sigma_mm, f"σ not given: estimated from the residuals of the "
                                      f"starting model, {fit.sigma_mm:.3g} mm")


def _starting_fit(model, measurements, params):
    """The point estimator's fit of ``model`` (σ̂ from its residuals), the toolkit's warnings
    kept in its words (as :func:`~doe_calib.estimation.identify.identify_quietly`)."""
    model = for_workload(model, FIT_PASSES * len(measurements.configurations))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DoeCalibWarning)
        return identify_point(model, provisional(measurements), params)
