"""The result of ``refine``: the models step by step, each added effect, the final model.

Plain data: a refine file is read back without building a model or loading
an effect file (the final fit is written by the CLI to its own file).
"""
from __future__ import annotations

from dataclasses import dataclass, field

from doe_calib.diagnosis.candidate import Candidate, FittedSize
from doe_calib.diagnosis.result import DiagnosisResult, numbered_notes
from doe_calib.io.json_file import read_json, write_json
from doe_calib.io.measurements import ESTIMATED, REPEATED

FORMAT = "doe_calib.refine"


@dataclass(frozen=True)
class RefineStep:
    """One model along the way: the effect just added and the errors of the grown model.

    Attributes
    ----------
    model : str
        The model at this step.
    added : str or None
        The effect string added at this step (None for the starting model).
    rms_mm, cv_rms_mm : float
        Fit residual and cross-validated RMS of this model, mm per coordinate.
    validation_rms_mm : float or None
        RMS on the validation readings, mm (when given).
    adequate : bool
        This model's diagnosis says it is adequate.
    reason : str
        Why this step, in words.
    fitted : tuple of FittedSize
        The added effect's fitted size ± std in display units.
    effect : Candidate or None
        The added effect as the previous model's diagnosis tested it (F, p, CV RMS
        before → after); None for the starting model and in files of earlier versions.
    """

    model: str
    added: str | None
    rms_mm: float
    cv_rms_mm: float
    validation_rms_mm: float | None
    adequate: bool
    reason: str
    fitted: tuple = ()
    effect: Candidate | None = None

    @property
    def cv_rms_before_mm(self) -> float | None:
        """Cross-validated RMS of the model before this step's effect, mm."""
        return None if self.effect is None else self.effect.cv_rms_before_mm

    def __str__(self) -> str:
        head = f"start: {self.model or '(base + markers)'}" if self.added is None \
            else f"+ {self.added}"
        cv = f"CV RMS {self.cv_rms_mm:.4f} mm" if self.cv_rms_before_mm is None else \
            f"CV RMS {self.cv_rms_before_mm:.4f} → {self.cv_rms_mm:.4f} mm"
        val = "" if self.validation_rms_mm is None else \
            f", validation {self.validation_rms_mm:.4f} mm"
        sizes = "".join(f"\n    {s}" for s in self.fitted)
        return f"{head}: fit RMS {self.rms_mm:.4f} mm, {cv}{val}{sizes}"

    def to_dict(self) -> dict:
        return {"model": self.model, "added": self.added, "rms_mm": self.rms_mm,
                "cv_rms_mm": self.cv_rms_mm, "validation_rms_mm": self.validation_rms_mm,
                "adequate": self.adequate, "reason": self.reason,
                "fitted": [s.to_dict() for s in self.fitted],
                "effect": None if self.effect is None else self.effect.to_dict()}

    @classmethod
    def from_dict(cls, d: dict) -> "RefineStep":
        """Inverse of :meth:`to_dict` (also the steps of earlier files)."""
        effect = d.get("effect")
        return cls(d["model"], d.get("added"), float(d["rms_mm"]), float(d["cv_rms_mm"]),
                   d.get("validation_rms_mm"), bool(d["adequate"]), d.get("reason", ""),
                   tuple(FittedSize.from_dict(r) for r in d.get("fitted", ())),
                   None if effect is None else Candidate.from_dict(effect))


@dataclass(frozen=True, eq=False)
class RefineResult:
    """The sequence of models, the final fit and its diagnosis.

    Attributes
    ----------
    steps : tuple of RefineStep
        The starting model, then one step per added effect.
    fit : IdentificationResult or None
        The final model's identification (what ``predict`` takes); None when
        read from a refine file (the CLI writes the fit to its own file).
    diagnosis : DiagnosisResult
        The final model's diagnosis.
    noise_floor_mm : float
    stopped : str
        Why refinement stopped, in words.
    notes : tuple of str
    """

    steps: tuple
    fit: object
    diagnosis: DiagnosisResult
    noise_floor_mm: float
    stopped: str
    notes: tuple = field(default=())

    @property
    def final(self) -> RefineStep:
        """The final model's step: its model string and fit, CV and validation RMS."""
        return self.steps[-1]

    @property
    def noise_words(self) -> str:
        """What :attr:`noise_floor_mm` is, in words: the readings' σ, or, when none was
        given, the σ of repeated readings, else σ̂ of the starting model's fit (which holds
        that model's misfit too)."""
        source = self.diagnosis.chi2.get("sigma_source")
        if source == ESTIMATED:
            return "σ̂ of the starting model's fit (no σ given)"
        if source == REPEATED:
            return "σ of repeated readings (no σ given)"
        return "noise floor"

    @property
    def added(self) -> tuple:
        """The added effects (:class:`Candidate`), in the order they were added."""
        return tuple(s.effect for s in self.steps[1:] if s.effect is not None)

    def __repr__(self) -> str:
        first, last = self.steps[0], self.steps[-1]
        return (f"<RefineResult {len(self.steps) - 1} effect(s) added: {last.model or '–'}; "
                f"CV RMS {first.cv_rms_mm:.4g} → {last.cv_rms_mm:.4g} mm>")

    def __str__(self) -> str:
        return self.summary()

    def summary(self) -> str:
        """The models step by step, each added effect with its size ± std and the CV RMS
        before → after, why refinement stopped."""
        lines = [f"{'step':<5}{'model':<58}{'fit RMS':>9}{'CV RMS':>9}{'valid.':>9}  adequate"]
        for i, s in enumerate(self.steps):
            v = f"{s.validation_rms_mm:9.4f}" if s.validation_rms_mm is not None else f"{'–':>9}"
            lines.append(f"{i:<5}{s.model[:57]:<58}{s.rms_mm:9.4f}{s.cv_rms_mm:9.4f}{v}  "
                         f"{'yes' if s.adequate else 'no'}")
        lines += [f"(mm per coordinate; {self.noise_words} {self.noise_floor_mm:.4f} mm)", "",
                  *[f"step {i}: {s.reason}" for i, s in enumerate(self.steps)], "",
                  f"stopped: {self.stopped}", *numbered_notes(self.notes)]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        return {"format": FORMAT, "steps": [s.to_dict() for s in self.steps],
                "noise_floor_mm": self.noise_floor_mm, "stopped": self.stopped,
                "final_model": self.final.model, "diagnosis": self.diagnosis.to_dict(),
                "notes": list(self.notes)}

    def to_json(self, path=None) -> str:
        return write_json(self.to_dict(), path)

    @classmethod
    def from_dict(cls, d: dict) -> "RefineResult":
        """Inverse of :meth:`to_dict`, without the fit (``fit`` is None): plain data, no
        model is built and no effect file read."""
        return cls(tuple(RefineStep.from_dict(s) for s in d["steps"]), None,
                   DiagnosisResult.from_dict(d["diagnosis"]), float(d["noise_floor_mm"]),
                   d["stopped"], tuple(d.get("notes", ())))

    @classmethod
    def from_json(cls, path) -> "RefineResult":
        return cls.from_dict(read_json(path, FORMAT, "refine history"))
