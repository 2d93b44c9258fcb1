"""``identify``: the model's parameters from marker readings, by any of the estimators.

``point`` (all marker coordinates, the method of this toolkit), ``two-step``
(the paper's alternation) and ``pose`` (full poses from the markers, only to
compare); every result ends with the plausibility findings.
"""
from __future__ import annotations

import warnings
from dataclasses import replace

from doe_calib.errors import (
    ConditioningWarning,
    ConvergenceWarning,
    DataWarning,
    DoeCalibWarning,
    MisfitWarning,
    PlausibilityWarning,
)
from doe_calib.estimation import plausibility
from doe_calib.estimation.fit_statistics import misfit_finding
from doe_calib.estimation.point_estimator import FIT_PASSES, identify_point
from doe_calib.estimation.selection import SELECTIONS, select as choose
from doe_calib.estimation.sigma import provisional, resolve_sigma
from doe_calib.io.repeated_readings import copies_words
from doe_calib.model.marker_model import for_workload

ESTIMATORS = ("point", "two-step", "pose")


def identify(model, measurements, params=None, estimator: str = "point", progress=None,
             sigma: float | None = None, select: str = "cv", **options):
    """Identify the model's parameters from marker readings.

    Parameters
    ----------
    model : Model
        From :func:`~doe_calib.model.marker_model.build_model`.
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
    progress : callable(done, total, note), optional
        Told of long steps (compiling the model, each iteration of ``point``).
    sigma : float, optional
        σ per coordinate, m, for every reading (it replaces the readings' own);
        default: theirs, or, when they have none, σ̂ of this fit
        (:func:`~doe_calib.estimation.sigma.resolve_sigma`).
    select : {"cv", "none"}
        ``cv`` (default): when the poses are few for the free parameters, leave at
        nominal, one at a time, the parameters the data separate least from the
        others, as long as that lowers the predicted error at new poses
        (leave-one-pose-out, :mod:`~doe_calib.estimation.selection`); the result's
        ``selection`` says which and why. ``none``: every parameter the data can
        separate is fitted.

    Returns
    -------
    IdentificationResult
        Its ``warnings`` end with the plausibility findings (σ̂/σ far from 1,
        units, placement errors as large as a link, collinear markers). When
        ``measurements.sigma_estimated``, σ is estimated from the residuals:
        ``sigma_mm`` is σ̂, the covariance is scaled to it, and the result says so.
        The σ of repeated readings, when poses were read more than once, is reported
        beside (``sigma_repeated``), never used in place of σ.
    """
    if select not in SELECTIONS:
        raise ValueError(f"unknown parameter selection {select!r}; choose one of "
                         f"{', '.join(SELECTIONS)}")
    if estimator not in ESTIMATORS:
        raise ValueError(f"unknown estimator {estimator!r}; choose one of "
                         f"{', '.join(ESTIMATORS)}")
    settled = resolve_sigma(model, measurements, sigma, in_fit=True)
    measurements = provisional(settled.measurements)
    model = for_workload(model, FIT_PASSES * len(measurements.configurations), progress)

    def fit(start):
        return replace(_estimate(model, measurements, start, estimator, progress, options),
                       sigma_repeated=settled.repeated)

    if select == "none":
        return with_plausibility(model, measurements, fit(params))
    said = {}  # each fit's warnings, held back: only the kept fit's are told

    def recorded(start):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            result = fit(start)
        said[id(result)] = caught
        return result

    first = recorded(params)
    kept, selection = choose(model, measurements, first, recorded)
    told = _told(said[id(first)], said[id(kept)]) if kept is not first else said[id(first)]
    for w in list(told):  # a copy: a caller recording warnings may hold the same list
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    notes = kept.warnings + tuple(n for n in first.warnings if n not in kept.warnings and n not in
                                  {str(w.message) for w in said[id(first)]
                                   if issubclass(w.category, OF_THAT_FIT)})
    return with_plausibility(model, measurements,
                             replace(kept, warnings=notes, selection=selection,
                                     absorbed=first.absorbed))


#: Warnings about one fit's numbers, not about the data: not carried to another fit.
OF_THAT_FIT = (ConditioningWarning, ConvergenceWarning)


def _told(first, kept):
    """The warnings to issue when a refit is kept: what the first fit found of the data (the
    parameters it cannot separate, told once), then the kept fit's own."""
    out = [w for w in first if not issubclass(w.category, OF_THAT_FIT)]
    seen = {(w.category, str(w.message)) for w in out}
    return out + [w for w in kept if (w.category, str(w.message)) not in seen]


def _estimate(model, measurements, params, estimator, progress, options):
    """One fit by the estimator named."""
    if estimator == "point":
        return identify_point(model, measurements, params, progress=progress, **options)
    if estimator == "two-step":
        from doe_calib.estimation.two_step import identify_two_step

        return identify_two_step(model, measurements, params, **options)
    from doe_calib.estimation.pose_estimator import identify_pose  # SciPy: loaded only for it

    return identify_pose(model, measurements, params, **options)


def with_plausibility(model, measurements, result):
    """``result`` with what looks wrong added to its warnings, each also issued.

    The :mod:`~doe_calib.estimation.plausibility` findings and a σ given that repeated
    readings contradict (:meth:`~doe_calib.estimation.repeatability.Repeatability.disagreement`)
    as :class:`~doe_calib.errors.PlausibilityWarning`; a clear rejection by the χ² test
    (:func:`~doe_calib.estimation.fit_statistics.misfit_finding`, in place of plausibility's
    σ̂/σ finding) as :class:`~doe_calib.errors.MisfitWarning`; readings present twice
    (:func:`~doe_calib.io.repeated_readings.copies_words`) as
    :class:`~doe_calib.errors.DataWarning`.
    """
    findings = plausibility.check(model, measurements, result)
    if result.sigma_repeated is not None and not result.sigma_estimated:
        findings += tuple(f for f in [result.sigma_repeated.disagreement(result.sigma_mm)] if f)
    misfit = misfit_finding(result.fit_statistics, result.sigma_mm)
    if misfit:
        said = plausibility.sigma_ratio_finding(result.sigma_ratio, result.sigma_mm)
        findings = tuple(f for f in findings if f != said)
    copies = copies_words(measurements, model.tool.names)
    issued = [(f, PlausibilityWarning) for f in findings] + \
        [(f, kind) for f, kind in ((misfit, MisfitWarning), (copies, DataWarning)) if f]
    for f, kind in issued:
        warnings.warn(f, kind, stacklevel=3)
    return replace(result, warnings=result.warnings + tuple(f for f, _ in issued)) \
        if issued else result


def identify_quietly(model, measurements, params=None, **options):
    """:func:`identify` for fits run many times (cross-validation, diagnosis, refinement).

    Identifiability, conditioning, convergence and plausibility trouble is not
    issued as warnings: it stays, in words, in the result's ``warnings``. The fit keeps
    every parameter (``select="none"``) unless ``select`` is given, so the models these
    callers compare are each fitted whole. Only the
    toolkit's own warnings (:class:`~doe_calib.errors.DoeCalibWarning`) are
    held back; numpy's, scipy's and CasADi's still reach the caller.
    """
    options.setdefault("select", "none")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DoeCalibWarning)
        return identify(model, measurements, params, **options)
