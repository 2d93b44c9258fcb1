"""A diagnosis: is the model adequate, where does it fail, which effect is missing — in words."""
from __future__ import annotations

from dataclasses import dataclass, field

from doe_calib.diagnosis.effect_tests import CandidateTest
from doe_calib.diagnosis.variables import Follows
from doe_calib.io.json_file import read_json, write_json

FORMAT = "doe_calib.diagnosis"


@dataclass(frozen=True, eq=False)
class DiagnosisResult:
    """What the residual of one fitted model says.

    Attributes
    ----------
    model : str
        The model diagnosed.
    rms_mm : float
        Fit residual RMS per coordinate, mm.
    cv_rms_mm : float
        Cross-validated RMS, mm (held out as ``cv_grouping`` says).
    noise_floor_mm : float
        The measurement σ per coordinate, mm (given, or from repeated readings).
    adequate : bool
        Residuals consistent with the noise: the χ² test at ``level`` passes,
        or σ̂/σ ≤ 1 + ``chi2["tolerance"]`` and no candidate makes a material gain.
    chi2 : dict
        ``statistic``, ``dof``, ``p_value``, ``sigma_source``, ``sigma_hat_mm``,
        ``sigma_ratio`` (σ̂/σ) and its 95 % ``sigma_ratio_interval``,
        ``tolerance``, ``chi2_adequate`` (the χ² test alone).
    candidates : tuple of CandidateTest
        Best first: significant ones by cross-validated RMS, then by statistic.
    follows : tuple of Follows
        Variables the residual size follows, strongest first.
    flagged : tuple of dict
        Poses far outside the noise (kept in the fit, only named).
    level : float
        Significance level of the adequacy test and of proposing an effect.
    verdict : str
        The conclusion in plain words.
    proposed : str or None
        The effect to add (model-string form): among the significant
        candidates, the one with the lowest cross-validated RMS, if it lowers
        it by at least ``min_gain``; None otherwise.
    cv_grouping : str
        What the cross-validation held out, in words.
    min_gain : float
        The material gain (fraction of the cross-validated RMS).
    gross_errors : tuple of str
        Poses whose readings look like gross errors (the misfit sits there and
        follows no variable); empty otherwise.
    """

    model: str
    rms_mm: float
    cv_rms_mm: float
    noise_floor_mm: float
    adequate: bool
    chi2: dict
    candidates: tuple
    follows: tuple
    flagged: tuple
    level: float
    verdict: str
    proposed: str | None = None
    n_observations: int = 0
    cv_grouping: str = ""
    min_gain: float = 0.02
    gross_errors: tuple = ()
    notes: tuple = field(default=())

    @property
    def significant(self) -> list[CandidateTest]:
        """Candidates significant at ``level`` (Bonferroni-adjusted), best first."""
        return [c for c in self.candidates if c.p_value < self.level]

    @property
    def best(self):
        """The proposed candidate (see ``proposed``), or None."""
        return next((c for c in self.candidates if c.spec == self.proposed), None)

    def summary(self, top: int = 8) -> str:
        """The verdict, the adequacy test, the ranked candidates and what the residual follows."""
        c = self.chi2
        ratio = c.get("sigma_ratio")
        interval = c.get("sigma_ratio_interval")
        lines = [f"Diagnosis of model {self.model or '(base + markers)'}",
                 f"residual RMS {self.rms_mm:.4f} mm, cross-validated {self.cv_rms_mm:.4f} mm "
                 f"({self.cv_grouping or 'by pose'}), noise floor {self.noise_floor_mm:.4f} mm "
                 f"(σ {c['sigma_source']})",
                 f"χ² = {c['statistic']:.1f} on {c['dof']} dof (p = {c['p_value']:.3g}); "
                 f"σ̂ = {c['sigma_hat_mm']:.4f} mm"
                 + (f", σ̂/σ = {ratio:.3f} [{interval[0]:.3f}, {interval[1]:.3f}]"
                    if ratio is not None else "")
                 + ": " + ("adequate" if self.adequate else "NOT adequate"), "", self.verdict, "",
                 f"{'candidate':<44}{'F':>10}{'p (adj.)':>11}{'explains':>10}{'CV RMS mm':>11}"]
        for t in self.candidates[:top]:
            cv = f"{t.cv_rms_mm:11.4f}" if t.cv_rms_mm is not None else f"{'–':>11}"
            lines.append(f"{t.spec:<44}{t.statistic:10.3g}{t.p_value:11.2g}"
                         f"{100 * t.explained_fraction:9.1f}%{cv}"
                         + ("  (implausible)" if t.implausible else ""))
        if len(self.candidates) > top:
            lines.append(f"… and {len(self.candidates) - top} more (JSON)")
        if self.follows:
            lines += ["", "Residual size follows (adjusted R²): " + ", ".join(
                f"{f.variable} {f.r2:.2f}" for f in self.follows[:5])]
        if self.flagged:
            lines += ["", f"{len(self.flagged)} poses far outside the noise (kept): " + ", ".join(
                f"{p['pose']} ({p['rms_mm']:.3f} mm)" for p in self.flagged[:10])]
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        return {"format": FORMAT, "model": self.model, "rms_mm": self.rms_mm,
                "cv_rms_mm": self.cv_rms_mm, "noise_floor_mm": self.noise_floor_mm,
                "adequate": self.adequate, "chi2": self.chi2, "level": self.level,
                "verdict": self.verdict, "proposed": self.proposed,
                "n_observations": self.n_observations, "cv_grouping": self.cv_grouping,
                "min_gain": self.min_gain, "gross_errors": list(self.gross_errors),
                "candidates": [t.to_dict() for t in self.candidates],
                "follows": [f.to_dict() for f in self.follows],
                "flagged_poses": list(self.flagged), "notes": list(self.notes)}

    def to_json(self, path=None) -> str:
        return write_json(self.to_dict(), path)

    @classmethod
    def from_dict(cls, d: dict) -> "DiagnosisResult":
        return cls(d["model"], d["rms_mm"], d["cv_rms_mm"], d["noise_floor_mm"], d["adequate"],
                   d["chi2"], tuple(CandidateTest.from_dict(t) for t in d["candidates"]),
                   tuple(Follows(**f) for f in d["follows"]), tuple(d["flagged_poses"]),
                   d["level"], d["verdict"], d.get("proposed"), d.get("n_observations", 0),
                   d.get("cv_grouping", ""), d.get("min_gain", 0.02),
                   tuple(d.get("gross_errors", ())), tuple(d.get("notes", ())))

    @classmethod
    def from_json(cls, path) -> "DiagnosisResult":
        return cls.from_dict(read_json(path, FORMAT, "doe_calib diagnosis"))
