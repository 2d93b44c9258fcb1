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

from dataclasses import dataclass, field

from doe_calib.diagnosis.cross_validation import validation_rms
from doe_calib.diagnosis.effect_tests import augmented
from doe_calib.diagnosis.engine import describe, diagnose
from doe_calib.diagnosis.result import DiagnosisResult
from doe_calib.estimation.identify import identify_quietly
from doe_calib.estimation.sigma import resolve_sigma
from doe_calib.io.json_file import read_json, write_json
from doe_calib.model.effects import parse_effect

FORMAT = "doe_calib.refine"


@dataclass(frozen=True)
class RefineStep:
    """One model along the way."""

    model: str
    added: str | None
    rms_mm: float
    cv_rms_mm: float
    validation_rms_mm: float | None
    adequate: bool
    reason: str
    fitted: tuple = ()

    def to_dict(self) -> dict:
        d = dict(self.__dict__)
        d["fitted"] = list(self.fitted)
        return d


@dataclass(frozen=True, eq=False)
class RefineResult:
    """The sequence of models, the final fit and its diagnosis.

    Attributes
    ----------
    steps : tuple of RefineStep
    fit : IdentificationResult
        The final model's identification (what ``predict`` takes).
    diagnosis : DiagnosisResult
        The final model's diagnosis.
    noise_floor_mm : float
    stopped : str
        Why refinement stopped, in words.
    """

    steps: tuple
    fit: object
    diagnosis: DiagnosisResult
    noise_floor_mm: float
    stopped: str
    notes: tuple = field(default=())

    def summary(self) -> str:
        lines = [f"{'step':<5}{'model':<58}{'fit RMS':>9}{'CV RMS':>9}{'valid.':>9}  adequate",
                 ]
        for i, s in enumerate(self.steps):
            v = f"{s.validation_rms_mm:9.4f}" if s.validation_rms_mm is not None else f"{'–':>9}"
            lines.append(f"{i:<5}{s.model[:57]:<58}{s.rms_mm:9.4f}{s.cv_rms_mm:9.4f}{v}  "
                         f"{'yes' if s.adequate else 'no'}")
        lines += [f"(mm per coordinate; noise floor {self.noise_floor_mm:.4f} mm)", "",
                  *[f"step {i}: {s.reason}" for i, s in enumerate(self.steps)], "",
                  f"stopped: {self.stopped}"]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        return {"format": FORMAT, "steps": [s.to_dict() for s in self.steps],
                "noise_floor_mm": self.noise_floor_mm, "stopped": self.stopped,
                "final_model": self.fit.model, "diagnosis": self.diagnosis.to_dict(),
                "notes": list(self.notes)}

    def to_json(self, path=None) -> str:
        return write_json(self.to_dict(), path)

    @staticmethod
    def steps_from_json(path) -> list[RefineStep]:
        """The steps of a refine file (for plots and reports)."""
        return [RefineStep(**{**s, "fitted": tuple(s.get("fitted", ()))})
                for s in read_json(path, FORMAT, "refine history")["steps"]]


def _size_words(rows) -> str:
    return "; ".join(f"{r['name']} = {r['value']:.3g}"
                     + (f" ± {r['std']:.2g}" if r["std"] is not None else " (fixed)")
                     + f" {r['unit']}" for r in rows)


def refine(model, measurements, validation=None, level: float = 0.01, max_steps: int = 5,
           min_gain: float = 0.02, folds: int = 5, grouping: str = "auto", progress=None,
           fit=None, sigma_mm: float | None = None) -> RefineResult:
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
    sigma_mm : float, optional
        σ per coordinate, mm, for every reading (replacing the readings' own).

    Returns
    -------
    RefineResult
    """
    settled = resolve_sigma(model, measurements, sigma_mm, fit=fit)
    if settled.measurements is not measurements:  # σ settled here: fit at that σ
        measurements, fit = settled.measurements, None
    fit = identify_quietly(model, measurements) if fit is None else fit
    steps, added, reason, fitted = [], None, "starting model", ()
    while True:
        diag = diagnose(model, measurements, fit, level, folds, grouping, min_gain=min_gain)
        val = validation_rms(model, fit.parameters.values, validation) \
            if validation is not None else None
        steps.append(RefineStep(model.spec, added, diag.rms_mm, diag.cv_rms_mm, val,
                                diag.adequate, reason, fitted))
        if progress:
            progress(len(steps) - 1, f"{model.spec or '(base + markers)'}: CV RMS "
                                     f"{diag.cv_rms_mm:.4f} mm")
        best = diag.best
        if best is None:
            stopped = ("no candidate effect is significant and lowers the cross-validated RMS "
                       f"by {min_gain:.0%}; " + ("the model is adequate" if diag.adequate else
                                                 "the model is not adequate: " + diag.verdict))
            break
        if len(steps) > max_steps:
            stopped = f"stopped after {max_steps} added effects ({best.spec} would be next)"
            break
        model, start = augmented(model, fit.parameters, parse_effect(best.spec))
        fit = identify_quietly(model, measurements, start, register=False)
        added, fitted = best.spec, best.fitted
        reason = (f"added {best.spec}, {describe(best, model.robot)}: "
                  f"{_size_words(best.fitted)}; cross-validated RMS {diag.cv_rms_mm:.4g} → "
                  f"{best.cv_rms_mm:.4g} mm (p = {best.p_value:.2g})"
                  + (f"; {best.implausible}" if best.implausible else ""))
    return RefineResult(tuple(steps), fit, diag, diag.noise_floor_mm, stopped,
                        (f"cross-validation: {diag.cv_grouping}",))
