"""``refine``: forward selection of effects on cross-validated error.

From the starting model, add the candidate effect that is significant
(Bonferroni over every candidate and shape tried) and lowers the
cross-validated RMS the most, by at least a material margin; re-identify;
repeat until no candidate does. Adequacy (residual against the noise) is
reported at each step but does not stop the growth: on a real robot several
effects add up, and each that predicts better is kept. Each step records the
effect, its fitted size ± std with unit, the fit, cross-validated and (when
a validation set is given) validation RMS: the error falling step by step.
"""
from __future__ import annotations

from doe_calib.diagnosis.cross_validation import validation_rms
from doe_calib.diagnosis.effect_tests import augmented
from doe_calib.diagnosis.diagnose import candidate_batch_for, diagnose
from doe_calib.diagnosis.refine_result import RefineResult, RefineStep
from doe_calib.diagnosis.settings import check_settings
from doe_calib.estimation.identify import identify_quietly
from doe_calib.estimation.sigma import resolve_sigma
from doe_calib.io.repeated_readings import copies_words
from doe_calib.io.setting_ranges import whole
from doe_calib.model.effects import parse_effect

__all__ = ["refine", "RefineResult", "RefineStep"]


def _size_words(sizes) -> str:
    return "; ".join(f"{s.name} = {s.value:.3g}"
                     + (f" ± {s.std:.2g}" if s.std is not None else " (fixed)")
                     + f" {s.unit}" for s in sizes)


def refine(model, measurements, validation=None, level: float = 0.01, max_steps: int = 5,
           min_gain: float = 0.02, folds: int = 5, grouping: str = "auto", progress=None,
           fit=None, registry=None, sigma: float | None = None,
           practical_um: float = 2.0, tolerance: float = 0.05,
           one_batch: bool = True, workers: int | None = None) -> RefineResult:
    """Grow ``model`` one effect at a time while an effect predicts materially better.

    Parameters
    ----------
    model : Model
        The starting model.
    measurements : Measurements
        Readings to fit, test and cross-validate on. Readings without σ are
        given the σ̂ of the starting model's fit, as on the command line
        (:func:`~doe_calib.estimation.sigma.resolve_sigma`).
    validation : Measurements, optional
        Held-out readings, only for reporting the validation RMS at each step
        (never used to choose).
    level : float
        Significance level (Bonferroni-adjusted over every candidate and shape).
    max_steps : int
        Effects added at most.
    min_gain : float
        An effect is added only if it lowers the cross-validated RMS by at
        least this fraction.
    folds, grouping :
        Cross-validation (:func:`~doe_calib.diagnosis.cross_validation.make_folds`).
    progress : callable, optional
        ``progress(step, text)`` after each step.
    fit : IdentificationResult, optional
        The starting model's fit to ``measurements``, when already at hand.
    registry : EffectRegistry, optional
        Whose catalogue the candidate effects come from (default the built-in one;
        user effects: ``DEFAULT_REGISTRY.with_file(path)``). A candidate whose
        fitted values are physically implausible (its parameters' bounds and
        plausible ranges, :func:`~doe_calib.diagnosis.diagnose.diagnose`) is not added.
    sigma : float, optional
        σ per coordinate, m, for every reading (replacing the readings' own).
    practical_um : float
        Practical size, µm: a misfit beyond the noise below it, with no material
        candidate, is adequate (as :func:`~doe_calib.diagnosis.diagnose.diagnose`).
    tolerance : float
        σ̂ within this fraction of σ, with no material candidate, is adequate (as
        :func:`~doe_calib.diagnosis.diagnose.diagnose`).
    one_batch : bool
        Build the starting model's candidates once, in one batch, and take every step's
        candidate columns and grown models from it
        (:meth:`~doe_calib.diagnosis.candidate_batch.CandidateBatch.within`); False builds
        them afresh at each step (the reference: the same choices, numbers equal to ~1e-12).
    workers : int, optional
        Threads fitting each step's candidates at once (:func:`~doe_calib.diagnosis.diagnose`;
        default the machine's cores, at most 4). The result does not depend on it.

    Returns
    -------
    RefineResult

    Raises
    ------
    OptionError
        A setting out of its range (:func:`~doe_calib.diagnosis.settings.check_settings`;
        ``max_steps`` a whole number ≥ 0).
    """
    check_settings(level, folds, min_gain, tolerance, practical_um, workers)
    whole("max_steps", max_steps, 0, "effects")
    settled = resolve_sigma(model, measurements, sigma, fit=fit)
    if settled.measurements is not measurements:  # σ settled here: fit at that σ
        measurements, fit = settled.measurements, None
    fit = identify_quietly(model, measurements) if fit is None else fit
    steps, added, reason, effect = [], None, "starting model", None
    batch = candidate_batch_for(model, measurements, registry) if one_batch else None
    while True:
        fitted = {}  # the candidates diagnose fitted: the chosen one is not fitted again
        diag = diagnose(model, measurements, fit, level, folds, grouping, min_gain=min_gain,
                        registry=registry, practical_um=practical_um,
                        tolerance=tolerance, candidate_fits=fitted, batch=batch,
                        workers=workers)
        val = validation_rms(model, fit.parameters.values, validation) \
            if validation is not None else None
        steps.append(RefineStep(model.spec, added, diag.rms_mm, diag.cv_rms_mm, val,
                                diag.adequate, reason, () if effect is None else effect.sizes,
                                effect))
        if progress:
            progress(len(steps) - 1, f"{model.spec or '(base + markers)'}: CV RMS "
                                     f"{diag.cv_rms_mm:.4f} mm")
        best = diag.best
        if diag.outliers:
            stopped = f"no effect tested: {diag.verdict}"
            break
        if best is None:
            stopped = ("no candidate effect is significant and lowers the cross-validated RMS "
                       f"by {min_gain:.0%}; " + ("the model is adequate" if diag.adequate else
                                                 "the model is not adequate: " + diag.verdict))
            break
        if len(steps) > max_steps:
            stopped = f"stopped after {max_steps} added effects ({best.spec} would be next)"
            break
        if best.spec in fitted:  # the same fit: model + effect from this fit's values
            model, fit = fitted[best.spec]
        else:
            model, start = augmented(model, fit.parameters, parse_effect(best.spec,
                                                                         registry=registry))
            fit = identify_quietly(model, measurements, start, register=False)
        added, effect = best.spec, best
        reason = (f"added {best.spec}, {best.words}: "
                  f"{_size_words(best.sizes)}; cross-validated RMS {diag.cv_rms_mm:.4g} → "
                  f"{best.cv_rms_mm:.4g} mm (p = {best.p_value:.2g})"
                  + (f"; {best.implausible}" if best.implausible else ""))
    copies = copies_words(measurements, model.tool.names)
    return RefineResult(tuple(steps), fit, diag, diag.noise_floor_mm, stopped,
                        (f"cross-validation: {diag.cv_grouping}",) + ((copies,) if copies else ()))
