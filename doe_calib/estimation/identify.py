"""``identify``: the model's parameters from marker readings, by any of the estimators.

``point`` (all marker coordinates, the method of this toolkit), ``two-step``
(the paper's alternation) and ``pose`` (full poses from the markers, only to
compare); every result ends with the plausibility findings.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, replace

from doe_calib.errors import (
    ConditioningWarning,
    ConvergenceWarning,
    DataError,
    DataWarning,
    DoeCalibWarning,
    MisfitWarning,
    OptionError,
    PlausibilityWarning,
)
from doe_calib.estimation import plausibility
from doe_calib.estimation.assembly import SIGMA_ESTIMATED
from doe_calib.estimation.fit_statistics import misfit_finding
from doe_calib.estimation.point_estimator import FIT_PASSES, identify_point
from doe_calib.estimation.selection import SELECTIONS, select as choose
from doe_calib.estimation.sigma import resolve_sigma
from doe_calib.estimation.planes import is_plane_note
from doe_calib.estimation.sockets import is_socket_note
from doe_calib.io.measurements import provisional
from doe_calib.io.repeated_readings import copies_words
from doe_calib.io.setting_ranges import positive, whole
from doe_calib.model.marker_model import for_workload

ESTIMATORS = ("point", "two-step", "pose")
#: The setting each estimator has alone.
OWN_SETTING = {"two-step": "tol", "pose": "normalisation"}


@dataclass(frozen=True)
class FitSettings:
    """How :func:`identify` fits, each setting checked on construction.

    Attributes
    ----------
    select : {"cv", "none"}
        ``cv``: when the poses are few for the free parameters, leave at nominal, one
        at a time, the parameters the data separate least from the others, as long as
        that lowers the predicted error at new poses (leave-one-pose-out,
        :mod:`~doe_calib.estimation.selection`); the result's ``selection`` says which
        and why. ``none``: every parameter the data can separate is fitted.
    register : bool
        Start the base pose from a point-set registration of the readings (False:
        from the start values, e.g. those of a fit the model grew from).
    max_iterations : int, optional
        Iterations (``two-step``: alternations) allowed, ≥ 1; default the
        estimator's own (200; 500 for ``two-step``).
    tol : float, optional
        ``two-step`` only: its convergence tolerance, > 0 (default 1e-10).
    normalisation : float, optional
        ``pose`` only: λ weighting orientation against position residuals, m/rad,
        > 0 (default from the tool).

    Raises
    ------
    OptionError
        A setting out of its range, naming it (``max_iterations=0: …``).
    """

    select: str = "cv"
    register: bool = True
    max_iterations: int | None = None
    tol: float | None = None
    normalisation: float | None = None

    def __post_init__(self):
        if self.select not in SELECTIONS:
            raise OptionError(f"select={self.select!r}: choose one of {', '.join(SELECTIONS)}")
        if self.max_iterations is not None:
            object.__setattr__(self, "max_iterations",
                               whole("max_iterations", self.max_iterations, 1, "iteration"))
        for name, unit in (("tol", ""), ("normalisation", "m/rad")):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, positive(name, getattr(self, name), unit))

    def options(self, estimator: str) -> dict:
        """The keyword arguments of ``estimator``'s own function.

        Raises
        ------
        OptionError
            An unknown estimator, or the setting of another one (``tol`` is
            ``two-step``'s, ``normalisation`` is ``pose``'s).
        """
        if estimator not in ESTIMATORS:
            raise OptionError(f"estimator={estimator!r}: choose one of {', '.join(ESTIMATORS)}")
        for other, name in OWN_SETTING.items():
            if other != estimator and getattr(self, name) is not None:
                raise OptionError(f"{name}={getattr(self, name)!r}: a setting of the {other} "
                                  f"estimator, not of {estimator}")
        names = ("max_iterations", OWN_SETTING.get(estimator))
        return {"register": self.register} | {n: getattr(self, n) for n in names
                                              if n and getattr(self, n) is not None}


#: What the estimators other than ``point`` need of every reading, in words.
NEEDS_XYZ = {"two-step": "the two-step estimator fits the base and markers to each reading's "
                         "x, y, z",
             "pose": "the pose estimator rebuilds each flange pose from its markers' x, y, z"}


def refuse_contacts(estimator: str, measurements) -> None:
    """Raise a DataError, in words a user acts on, when ``estimator`` is not ``point`` and
    some of ``measurements`` are socket contacts."""
    n = int(measurements.contact.sum())
    if n and estimator != "point":
        raise DataError(f"{NEEDS_XYZ[estimator]}; {n} of these {len(measurements)} readings "
                        f"are socket contacts, which have none (the ball sat in a socket whose "
                        f"position is unknown). Use the point estimator (the default: "
                        f"--estimator point, or leave --estimator out), which compares each "
                        f"contact to its socket's point, fitted with the robot",
                        measurements.source or None)


#: The settings of fits run many times to compare models: every parameter kept.
WHOLE = FitSettings(select="none")


def identify(model, measurements, params=None, *, estimator: str = "point",
             settings: FitSettings | None = None, sigma: float | None = None,
             progress=None):
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
        for comparison.
    settings : FitSettings, optional
        Parameter selection, iterations and the estimator's own setting (default
        ``FitSettings()``: selection ``cv``).
    sigma : float, optional
        σ per coordinate, m, for every reading (it replaces the readings' own);
        default: theirs, or, when they have none, σ̂ of this fit
        (:func:`~doe_calib.estimation.sigma.resolve_sigma`).
    progress : callable, optional
        ``progress(done, total, note)`` told of long steps: compiling the model
        (``total`` None), each iteration of ``point`` (``total`` its limit).

    Returns
    -------
    IdentificationResult
        Its ``warnings`` end with the plausibility findings (σ̂/σ far from 1,
        units, placement errors as large as a link, collinear markers). When
        ``measurements.sigma_estimated``, σ is estimated from the residuals:
        ``sigma_mm`` is σ̂, the covariance is scaled to it, and the result says so.
        The σ of repeated readings, when poses were read more than once, is reported
        beside (``sigma_repeated``), never used in place of σ.

    Raises
    ------
    DataError
        ``two-step`` or ``pose`` on readings with socket contacts (what to use instead).
    """
    settings = FitSettings() if settings is None else settings
    options = settings.options(estimator)
    refuse_contacts(estimator, measurements)
    settled = resolve_sigma(model, measurements, sigma, in_fit=True)
    measurements = provisional(settled.measurements)
    model = for_workload(model, FIT_PASSES * len(measurements.configurations), progress)

    def fit(start):
        return replace(_estimate(model, measurements, start, estimator, progress, options),
                       sigma_repeated=settled.repeated)

    if settings.select == "none":
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
    of_that_fit = {str(w.message) for w in said[id(first)] if issubclass(w.category, OF_THAT_FIT)}
    notes = kept.warnings + tuple(n for n in first.warnings if n not in kept.warnings
                                  and n not in of_that_fit and not n.startswith(SIGMA_ESTIMATED)
                                  and not is_socket_note(n) and not is_plane_note(n))
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


def identify_quietly(model, measurements, params=None, *, settings: FitSettings = WHOLE,
                     sigma: float | None = None):
    """:func:`identify` for fits run many times (cross-validation, diagnosis, refinement).

    Identifiability, conditioning, convergence and plausibility trouble is not
    issued as warnings: it stays, in words, in the result's ``warnings``. The fit keeps
    every parameter (:data:`WHOLE`, ``select="none"``) unless ``settings`` say
    otherwise, so the models these callers compare are each fitted whole. Only the
    toolkit's own warnings (:class:`~doe_calib.errors.DoeCalibWarning`) are
    held back; numpy's, scipy's and CasADi's still reach the caller.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DoeCalibWarning)
        return identify(model, measurements, params, settings=settings, sigma=sigma)
