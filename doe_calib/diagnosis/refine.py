"""``refine``: add the best significant effect, re-identify, repeat until the model is adequate.

Each step is recorded with its fit RMS, cross-validated RMS and, when a
validation set is given, the RMS on it — the error falling step by step.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from ..effects import parse_effect
from ..identify import identify_quietly
from ..jsonfile import read_json, write_json
from ..measurement import build_model
from .candidates import augmented
from .cross_validation import validation_rms
from .engine import describe, diagnose
from .result import DiagnosisResult

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

    def to_dict(self) -> dict:
        return dict(self.__dict__)


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
        return [RefineStep(**s) for s in read_json(path, FORMAT, "refine history")["steps"]]


def refine(model, measurements, validation=None, level: float = 0.01, max_steps: int = 5,
           min_gain: float = 0.01, progress=None, fit=None) -> RefineResult:
    """Grow ``model`` one effect at a time until it is adequate.

    Parameters
    ----------
    model : Model
        The starting model.
    measurements : Measurements
        Readings to fit and cross-validate on.
    validation : Measurements, optional
        Held-out readings, only for reporting the validation RMS at each step.
    level : float
        Significance level (adequacy and proposing an effect).
    max_steps : int
        Effects added at most.
    min_gain : float
        An effect is added only if it lowers the cross-validated RMS by at
        least this fraction.
    progress : callable, optional
        ``progress(step, text)`` after each step.
    fit : IdentificationResult, optional
        The starting model's fit to ``measurements``, when already at hand.

    Returns
    -------
    RefineResult
    """
    fit = identify_quietly(model, measurements) if fit is None else fit
    steps, added, reason = [], None, "starting model"
    while True:
        diag = diagnose(model, measurements, fit, level)
        val = validation_rms(model, fit.parameters.values, validation) \
            if validation is not None else None
        steps.append(RefineStep(model.spec, added, diag.rms_mm, diag.cv_rms_mm, val,
                                diag.adequate, reason))
        if progress:
            progress(len(steps) - 1, f"{model.spec}: CV RMS {diag.cv_rms_mm:.4f} mm")
        best = diag.best
        if diag.adequate and best is None:
            stopped = "the model is adequate and no further effect is significant"
            break
        if best is None:
            stopped = ("no catalogue effect explains the residual although the model is not "
                       "adequate: " + diag.verdict)
            break
        if best.cv_rms_mm is None or best.cv_rms_mm > diag.cv_rms_mm * (1 - min_gain):
            stopped = (f"the best significant effect, {best.spec}, does not lower the "
                       f"cross-validated RMS by {min_gain:.0%}")
            break
        if len(steps) > max_steps:
            stopped = f"stopped after {max_steps} added effects"
            break
        effect = parse_effect(best.spec)
        model, start = augmented(model, fit.parameters, effect)
        model = build_model(model.robot, model.tool, model.effects)
        fit = identify_quietly(model, measurements, start, register=False)
        added = best.spec
        reason = (f"added {best.spec}: {describe(best, model.robot)} explained "
                  f"{100 * best.explained_fraction:.0f} % of the residual (p = "
                  f"{best.p_value:.2g})")
    return RefineResult(tuple(steps), fit, diag, diag.noise_floor_mm, stopped)
