"""``refine``: forward selection of effects on cross-validated error.

From the starting model, add the effect :func:`~doe_calib.diagnosis.diagnose.diagnose`
proposes, re-identify, and repeat until none is proposed. Adequacy is reported at
each step but does not stop the growth: on a real robot several effects add up.
Each step records the effect, its fitted size ± std with unit, the fit,
cross-validated and (with a validation set) validation RMS.
"""
from __future__ import annotations

from doe_calib.diagnosis.candidate import sizes_words
from doe_calib.diagnosis.candidate_scoring import GROWN
from doe_calib.diagnosis.cross_validation import validation_rms
from doe_calib.diagnosis.diagnose import diagnose, settled_fit
from doe_calib.diagnosis.refine_result import RefineResult, RefineStep
from doe_calib.diagnosis.settings import RefineSettings
from doe_calib.estimation.effect_signature import augmented
from doe_calib.estimation.identify import identify_quietly
from doe_calib.io.repeated_readings import copies_words
from doe_calib.model.effects import parse_effect

__all__ = ["refine", "RefineResult", "RefineStep"]


def refine(model, measurements, validation=None, *, settings: RefineSettings | None = None,
           fit=None, sigma: float | None = None, registry=None,
           progress=None) -> RefineResult:
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
    settings : RefineSettings, optional
        Each step's diagnosis settings and ``max_steps``, the effects added at most
        (:class:`~doe_calib.diagnosis.settings.RefineSettings`; default its defaults).
    fit : IdentificationResult, optional
        The starting model's fit to ``measurements``, when already at hand.
    sigma : float, optional
        σ per coordinate, m, for every reading (replacing the readings' own).
    registry : EffectRegistry, optional
        Whose catalogue the candidate effects come from (default the built-in one;
        user effects: ``DEFAULT_REGISTRY.with_file(path)``).
    progress : callable, optional
        ``progress(done, total, note)`` after each step: effects added so far, None
        (the steps are not known ahead), the model and its cross-validated RMS.

    Returns
    -------
    RefineResult
    """
    s = RefineSettings() if settings is None else settings
    settled, fit = settled_fit(model, measurements, sigma, fit)
    measurements = settled.measurements
    steps, added, reason, effect = [], None, "starting model", None
    while True:
        diag = diagnose(model, measurements, fit, settings=s, registry=registry)
        val = validation_rms(model, fit.parameters.values, validation, measurements) \
            if validation is not None else None
        steps.append(RefineStep(model.spec, added, diag.rms_mm, diag.cv_rms_mm, val,
                                diag.adequate, reason, () if effect is None else effect.sizes,
                                effect))
        if progress:
            progress(len(steps) - 1, None, f"{model.spec or '(base + markers)'}: CV RMS "
                                           f"{diag.cv_rms_mm:.4f} mm")
        best = diag.best
        if diag.outliers:
            stopped = f"no effect tested: {diag.verdict}"
            break
        if best is None:
            stopped = ("no candidate effect is significant and lowers the cross-validated RMS "
                       f"by {s.min_gain:.0%}; " + ("the model is adequate" if diag.adequate else
                                                 "the model is not adequate: " + diag.verdict))
            break
        if len(steps) > s.max_steps:
            stopped = f"stopped after {s.max_steps} added effects ({best.spec} would be next)"
            break
        model, start = augmented(model, fit.parameters, parse_effect(best.spec, registry=registry))
        fit = identify_quietly(model, measurements, start, settings=GROWN)
        added, effect = best.spec, best
        reason = (f"added {best.spec}, {best.words}: {sizes_words(best.sizes, ' (fixed)')}; "
                  f"cross-validated RMS {diag.cv_rms_mm:.4g} → "
                  f"{best.cv_rms_mm:.4g} mm (p = {best.p_value:.2g})"
                  + (f"; {best.implausible}" if best.implausible else ""))
    copies = copies_words(measurements, model.tool.names)
    return RefineResult(tuple(steps), fit, diag, diag.noise_floor_mm, stopped,
                        (f"cross-validation: {diag.cv_grouping}",) + ((copies,) if copies else ()))
